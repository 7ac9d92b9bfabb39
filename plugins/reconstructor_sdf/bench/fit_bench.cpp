// Cost of one object update: fitObject with the shipped prior on 200 (and 60) noisy points of one side
// and the front of a car, start 0.5 m and 10 degrees off (one thread); and the monocular update the
// plugin makes by default: 60 points of map-point noise plus the silhouettes of 3 keyframes, a 6 x 6 (and
// 8 x 8) lattice each.
//   cmake -DBESLAM_BUILD_BENCHMARKS=ON ... && build/bin/reconstructor_sdf_fit_bench
#include <benchmark/benchmark.h>

#include "fit/object_fit.hpp"
#include "fit/silhouette.hpp"

using namespace beslam::recon;

namespace {

// The car shape prior the plugin ships, loaded once.
const shape::ShapePrior& shippedPrior() {
  static const shape::ShapePrior prior =
      shape::ShapePrior::load(std::string(BESLAM_SOURCE_DIR) + "/plugins/reconstructor_sdf/data/car_shape_prior.bsdf");
  return prior;
}

// The benchmark car's pose: 8 m ahead and 3 m to the side, turned 0.4 rad.
Eigen::Isometry3d truePose() {
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
  T_true.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_true.translation() = Eigen::Vector3d(8, 3, 0.75);
  return T_true;
}

// The fit's start: 0.5 m and 10 degrees off T_true.
Eigen::Isometry3d startPose(const Eigen::Isometry3d& T_true) {
  Eigen::Isometry3d T_init = T_true;
  T_init.translation() += Eigen::Vector3d(0.35, -0.35, 0);
  T_init.linear() = T_true.linear() * Eigen::AngleAxisd(0.17, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T_init;
}

// Times one fitObject with the shipped prior per benchmark iteration; the last fit's Levenberg-Marquardt
// iterations are the counter lm_iterations.
void timeFits(benchmark::State& state, const Eigen::Isometry3d& T_init, const Eigen::Vector3d& size,
              const Eigen::VectorXd& z0, const fit::FitObservations& obs, const fit::FitOptions& options) {
  int iterations = 0;
  for (auto _ : state) {
    const fit::FitResult r = fit::fitObject(shippedPrior(), T_init, size, z0, obs, options);
    if (!r.ok) state.SkipWithError(r.why.c_str());
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.cost);
  }
  state.counters["lm_iterations"] = iterations;
}

void BM_FitObject(benchmark::State& state) {
  const shape::ShapePrior& prior = shippedPrior();
  const int n = static_cast<int>(state.range(0));
  const Eigen::Vector3d size(4.6, 1.8, 1.5);
  Eigen::VectorXd z_true = Eigen::VectorXd::Zero(prior.dimensions());
  z_true(0) = 0.5 * prior.codeStd()(0);
  const Eigen::Isometry3d T_true = truePose();
  fit::FitObservations obs;
  shape::Random rng(1);
  for (const auto& p : prior.surfaceSamples(z_true, size, 8 * n, 3)) {
    if (p.y() < 0 || (p.x() < 0 && p.y() < 0.6)) continue;  // the left side and the front
    if (static_cast<int>(obs.p_world.size()) == n) break;
    obs.p_world.push_back(
        T_true * (p + 0.02 * Eigen::Vector3d(rng.uniform(-1.7, 1.7), rng.uniform(-1.7, 1.7), rng.uniform(-1.7, 1.7))));
  }
  const Eigen::Isometry3d T_init = startPose(T_true);
  const Eigen::VectorXd z0 = Eigen::VectorXd::Zero(prior.dimensions());
  timeFits(state, T_init, size, z0, obs, fit::FitOptions());
  state.counters["points"] = static_cast<double>(obs.p_world.size());
}
BENCHMARK(BM_FitObject)->Arg(200)->Arg(60)->Unit(benchmark::kMillisecond);

void BM_FitObjectWithSilhouettes(benchmark::State& state) {
  const shape::ShapePrior& prior = shippedPrior();
  const int grid = static_cast<int>(state.range(0));
  const Eigen::Vector3d size(4.6, 1.8, 1.5);
  const Eigen::VectorXd z0 = Eigen::VectorXd::Zero(prior.dimensions());
  const Eigen::Isometry3d T_true = truePose();
  fit::FitObservations obs;
  shape::Random rng(1);
  for (const auto& p : prior.surfaceSamples(z0, size, 480, 3)) {  // map points: 0.15 m noise
    if (p.y() < 0 || (p.x() < 0 && p.y() < 0.6)) continue;
    if (obs.p_world.size() == 60) break;
    obs.p_world.push_back(
        T_true * (p + 0.15 * Eigen::Vector3d(rng.uniform(-1.7, 1.7), rng.uniform(-1.7, 1.7), rng.uniform(-1.7, 1.7))));
  }
  const double s[3] = {size.x(), size.y(), size.z()};
  for (int view = 0; view < 3; ++view) {  // a camera passing at 8 m, 20 degrees apart
    const double bearing = 0.9 + 0.35 * view;
    const Eigen::Vector3d cam_obj(8 * std::cos(bearing), 8 * std::sin(bearing), 0.9);
    const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(-cam_obj).normalized();
    for (int r = 0; r < grid; ++r)
      for (int c = 0; c < grid; ++c) {
        const Eigen::Vector3d target =
            side * ((c + 0.5) / grid - 0.5) * 6.0 + Eigen::Vector3d(0, 0, ((r + 0.5) / grid - 0.5) * 2.2);
        const Eigen::Vector3d u = (target - cam_obj).normalized();
        const double ov[3] = {cam_obj.x(), cam_obj.y(), cam_obj.z()}, uv[3] = {u.x(), u.y(), u.z()};
        const bool inside = fit::leastLevel(prior, ov, uv, s, z0.data(), nullptr) <= 0;
        obs.silhouette.push_back({T_true * cam_obj, T_true.linear() * u, inside, 1.0});
      }
  }
  const Eigen::Isometry3d T_init = startPose(T_true);
  fit::FitOptions options;  // the plugin's monocular settings (settings.json)
  options.sigma_m = 0.15, options.huber_m = 0.3, options.inlier_m = 0.3, options.sigma_silhouette_m = 0.4;
  timeFits(state, T_init, size, z0, obs, options);
  state.counters["rays"] = static_cast<double>(obs.silhouette.size());
}
BENCHMARK(BM_FitObjectWithSilhouettes)->Arg(6)->Arg(8)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
