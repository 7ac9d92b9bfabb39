// Google Benchmark: the costs issue 18 names for place recognition and loop correction.
// BM_PlaceQuery300: one relocalisation / loop query of a keyframe against a database of 300 keyframes
// (target under 5 ms): the keyframes sharing words with it, then the ORB-SLAM2 candidate scoring. The
// keyframes are KITTI 00 frames 0-199 and then 0-99 again (the shared data), else synthetic textured
// images, with 2000 features each and the default vocabulary's words.
// BM_LoopCorrection300: the essential-graph optimisation of a 300-keyframe loop (target under 1 s): a
// chain of keyframes 1 m apart round a circle with 2 % scale drift and a heading drift, its spanning-tree
// and covisibility edges, and the loop edge that closes it; Sim(3) (argument 0) and SE(3) (argument 1).
// BM_GlobalBa300: the global BA that follows it (10 iterations, as loop_global_ba_iterations) on a map of
// 300 keyframes down a road, 20 points a metre, each seen by the keyframes it is 4-30 m ahead of; Ceres'
// sparse Schur LM (first argument 0) or our block-sparse one (1, loop_global_ba_solver: schur); keyframes
// 4 m apart as on KITTI (second argument 4: 24,375 points seen by 6 keyframes each) or 1 m apart (1: 6,439
// points seen by 22 each, a denser reduced system). A whole loop correction is the essential graph, the
// fusion and this global BA.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "beslam_orb/orb_slam.hpp"
#include "features/orb_extractor.hpp"
#include "loop/pose_graph.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map_builder.hpp"
#include "optimize/bundle_adjustment.hpp"
#include "place/keyframe_database.hpp"
#include "place/vocabulary.hpp"
#include "test_util.hpp"

namespace {

using namespace beslam::orb;

constexpr int kKeyFrames = 300;

struct PlaceFixture {
  place::Vocabulary vocabulary;
  Map map;
  KeyFrameDatabase database;
  std::vector<KeyFrame*> keyframes;
  bool ok = false;
};

// Built once: extracting 300 frames takes seconds.
PlaceFixture& placeFixture() {
  static PlaceFixture* f = [] {
    auto* fx = new PlaceFixture;
    const std::string vocab = BESLAM_SOURCE_DIR "/plugins/backend_orb/data/orb_vocabulary.bvoc";
    if (!std::filesystem::exists(vocab)) return fx;
    fx->vocabulary = place::Vocabulary::load(vocab);
    ExtractorOptions eo;
    eo.features = 2000;
    const OrbExtractor extractor(eo);
    for (int k = 0; k < kKeyFrames; ++k) {
      char name[64];
      std::snprintf(name, sizeof(name), "/kitti/odometry/sequences/00/image_0/%06d.png", k % 200);
      cv::Mat image = cv::imread(BESLAM_SHARED_DATA + std::string(name), cv::IMREAD_GRAYSCALE);
      if (image.empty()) image = test::texturedImage(1241, 376, static_cast<uint64_t>(k % 200) + 1);
      Frame frame(k, 0.1 * k, extractor.extract(image, cv::Mat()));
      fx->vocabulary.transform(frame.features->descriptors, frame.bow, &frame.feature_vector, 4);
      Camera camera;
      camera.width = image.cols, camera.height = image.rows;
      camera.fx = camera.fy = 718.856, camera.cx = 607.1928, camera.cy = 185.2157;
      KeyFrame* kf = fx->map.createKeyFrame(frame, camera, extractor.pyramid());
      fx->database.add(kf);
      fx->keyframes.push_back(kf);
    }
    fx->ok = true;
    return fx;
  }();
  return *f;
}

void BM_PlaceQuery300(benchmark::State& state) {
  PlaceFixture& f = placeFixture();
  if (!f.ok) {
    state.SkipWithError("no vocabulary file");
    return;
  }
  size_t q = 0, candidates = 0;
  for (auto _ : state) {
    const KeyFrame* kf = f.keyframes[(37 * q++) % f.keyframes.size()];
    const auto found = f.database.relocalisationCandidates(kf->bow);
    candidates += found.size();
    benchmark::DoNotOptimize(found.data());
  }
  state.counters["keyframes"] = static_cast<double>(f.keyframes.size());
  state.counters["candidates"] =
      benchmark::Counter(static_cast<double>(candidates), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_PlaceQuery300)->Unit(benchmark::kMillisecond);

// A drifted loop of n keyframes: truth on a circle, estimate integrated from odometry with a scale and a
// heading drift; edges between consecutive keyframes (spanning tree) and to the keyframe after next
// (covisibility), measured from the estimate; the loop edge from the truth.
loop::PoseGraph drifted(int n) {
  const double radius = n / (2 * M_PI);  // 1 m between keyframes
  auto truth = [&](int k) {
    const double a = 2 * M_PI * k / n;
    Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
    T_wc.linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T_wc.translation() = Eigen::Vector3d(radius * std::sin(a), 0, radius * (1 - std::cos(a)));
    return loop::Sim3::fromIsometry(T_wc.inverse());
  };
  loop::PoseGraph g;
  g.S_cw.push_back(truth(0));
  for (int k = 1; k < n; ++k) {
    loop::Sim3 step = truth(k) * truth(k - 1).inverse();  // camera k-1 -> k
    step.t *= 1.0 + 0.02 * k / n;                         // the map shrinks along the loop
    step.R = Eigen::AngleAxisd(1e-4, Eigen::Vector3d::UnitY()).toRotationMatrix() * step.R;
    g.S_cw.push_back(step * g.S_cw.back());
  }
  g.fixed.assign(n, false);
  g.fixed[0] = true;
  for (int k = 1; k < n; ++k) g.edges.push_back({k, k - 1, g.S_cw[k] * g.S_cw[k - 1].inverse(), 1.0});
  for (int k = 2; k < n; ++k) g.edges.push_back({k, k - 2, g.S_cw[k] * g.S_cw[k - 2].inverse(), 0.5});
  g.edges.push_back({n - 1, 0, truth(n - 1) * truth(0).inverse(), 1.0});
  return g;
}

void BM_LoopCorrection300(benchmark::State& state) {
  const loop::PoseGraph g = drifted(kKeyFrames);
  const bool fix_scale = state.range(0) != 0;
  int iterations = 0;
  for (auto _ : state) {
    const loop::PoseGraphResult r = loop::optimizePoseGraph(g, 20, fix_scale);
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.final_cost);
  }
  state.counters["iterations"] = iterations;
  state.SetLabel(fix_scale ? "SE3" : "Sim3");
}
BENCHMARK(BM_LoopCorrection300)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_GlobalBa300(benchmark::State& state) {
  const optimize::BaSolver solver = state.range(0) != 0 ? optimize::BaSolver::SchurLm : optimize::BaSolver::Ceres;
  const double spacing = static_cast<double>(state.range(1));
  const Camera camera{1241, 376, 718.856, 718.856, 607.1928, 185.2157};
  const ScalePyramid pyramid(8, 1.2);
  optimize::BundleAdjustmentReport report;
  for (auto _ : state) {
    state.PauseTiming();
    auto map = std::make_unique<Map>();
    test::buildRoad(*map, camera, pyramid, kKeyFrames, 20, 11, spacing);
    state.ResumeTiming();
    report = optimize::globalBundleAdjustment(*map, 10, optimize::plainOptions(solver));
    benchmark::DoNotOptimize(report.final_cost);
    state.PauseTiming();
    map.reset();
    state.ResumeTiming();
  }
  state.counters["points"] = report.points;
  state.counters["observations"] = report.observations;
  state.SetLabel(solver == optimize::BaSolver::SchurLm ? "schur" : "ceres");
}
BENCHMARK(BM_GlobalBa300)->ArgsProduct({{0, 1}, {4, 1}})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
