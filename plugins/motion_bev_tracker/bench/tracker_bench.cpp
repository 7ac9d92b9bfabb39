// Google Benchmark: one tracker frame with N boxes (parked and moving cars seen from a moving camera),
// after 20 frames of warm-up. Target: under 1 ms per frame for 50 boxes.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "beslam/motion/bev_tracker.hpp"

namespace {

// n cars in front of a camera that drives at 8 m/s: two thirds parked along the road (they scroll past
// and come back, so the scene stays full), a third driving back and forth at up to 8 m/s.
std::vector<beslam_box3d> scene(int n, int k, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<beslam_box3d> boxes;
  for (int i = 0; i < n; ++i) {
    const bool moving = i % 3 == 0;
    const double x = (i % 2 ? -1.0 : 1.0) * (3.0 + 3.0 * (i % 5));
    const double z0 = 5.0 + 60.0 * i / n;
    const double z_world =
        moving ? 0.8 * k + z0 + 10.0 * std::sin(0.08 * k) : z0 + 60.0 * std::floor((0.8 * k - z0 + 60.0) / 60.0);
    beslam_box3d b{};
    b.class_id = BESLAM_CLASS_CAR;
    b.track_id = -1;
    b.center_cam[0] = x + noise(rng);
    b.center_cam[1] = 1.0;
    b.center_cam[2] = z_world - 0.8 * k + noise(rng);
    b.size[0] = 4.2, b.size[1] = 1.8, b.size[2] = 1.5;
    b.score = 0.9f;
    boxes.push_back(b);
  }
  return boxes;
}

void BM_TrackerFrame(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  beslam::motion::Params p;
  p.association = state.range(1) ? "iou" : "distance";
  beslam::motion::BevTracker tracker(p);
  std::mt19937_64 rng(1);
  int k = 0;
  auto step = [&]() {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().z() = 0.8 * k;
    std::vector<beslam_box3d> boxes = scene(n, k, rng);
    tracker.classify(0.1 * k, T, boxes);
    ++k;
    return boxes;
  };
  for (int warm = 0; warm < 20; ++warm) step();
  for (auto _ : state) {
    state.PauseTiming();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().z() = 0.8 * k;
    std::vector<beslam_box3d> boxes = scene(n, k, rng);
    state.ResumeTiming();
    tracker.classify(0.1 * k, T, boxes);
    benchmark::DoNotOptimize(boxes.data());
    ++k;
  }
  state.counters["tracks"] = static_cast<double>(tracker.trackCount());
}

}  // namespace

BENCHMARK(BM_TrackerFrame)->Args({10, 0})->Args({50, 0})->Args({100, 0})->Args({50, 1})->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
