// Cost of one object update: fitObject with the shipped prior on 200 (and 60) noisy points of one side
// and the front of a car, start 0.5 m and 10 degrees off (one thread).
//   cmake -DBESLAM_BUILD_BENCHMARKS=ON ... && build/bin/reconstructor_sdf_fit_bench
#include <benchmark/benchmark.h>

#include "fit/object_fit.hpp"

using namespace beslam::recon;

namespace {

void BM_FitObject(benchmark::State& state) {
  static const shape::ShapePrior prior =
      shape::ShapePrior::load(std::string(BESLAM_SOURCE_DIR) + "/plugins/reconstructor_sdf/data/car_shape_prior.bsdf");
  const int n = static_cast<int>(state.range(0));
  const Eigen::Vector3d size(4.6, 1.8, 1.5);
  Eigen::VectorXd z_true = Eigen::VectorXd::Zero(prior.dimensions());
  z_true(0) = 0.5 * prior.codeStd()(0);
  Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
  T_true.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_true.translation() = Eigen::Vector3d(8, 3, 0.75);
  fit::FitObservations obs;
  shape::Random rng(1);
  for (const auto& p : prior.surfaceSamples(z_true, size, 8 * n, 3)) {
    if (p.y() < 0 || (p.x() < 0 && p.y() < 0.6)) continue;  // the left side and the front
    if (static_cast<int>(obs.p_world.size()) == n) break;
    obs.p_world.push_back(
        T_true * (p + 0.02 * Eigen::Vector3d(rng.uniform(-1.7, 1.7), rng.uniform(-1.7, 1.7), rng.uniform(-1.7, 1.7))));
  }
  Eigen::Isometry3d T_init = T_true;
  T_init.translation() += Eigen::Vector3d(0.35, -0.35, 0);
  T_init.linear() = T_true.linear() * Eigen::AngleAxisd(0.17, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::VectorXd z0 = Eigen::VectorXd::Zero(prior.dimensions());
  int iterations = 0;
  for (auto _ : state) {
    const fit::FitResult r = fit::fitObject(prior, T_init, size, z0, obs, fit::FitOptions());
    if (!r.ok) state.SkipWithError(r.why.c_str());
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.cost);
  }
  state.counters["points"] = static_cast<double>(obs.p_world.size());
  state.counters["lm_iterations"] = iterations;
}
BENCHMARK(BM_FitObject)->Arg(200)->Arg(60)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
