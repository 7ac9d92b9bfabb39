// Google Benchmark: replaying real PointRCNN detections (KITTI tracking 0000, AB3DMOT rows of the three
// classes). BM_ReplayLoadAnd100Frames parses the sequence's files and hands out 100 frames, reported per
// frame (the target: under 1 ms per frame); BM_ReplayFrame is one frame's lookup and copy after loading.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "beslam/detector_replay/replay.hpp"

namespace {

namespace fs = std::filesystem;
using namespace beslam::detector_replay;

const fs::path kRoot = fs::path(BESLAM_SHARED_DATA) / "kitti/tracking/training/det_pointrcnn";

DetectionTable load() {
  DetectionTable table;
  Report report;
  Filter filter;
  filter.min_score = 0.8;
  for (const char* cls : {"Car", "Pedestrian", "Cyclist"})
    readAb3dmotFile((kRoot / cls / "0000.txt").string(), filter, Policy::stop, ScoreTransform::sigmoid, table, report);
  return table;
}

void BM_ReplayLoadAnd100Frames(benchmark::State& state) {
  if (!fs::exists(kRoot)) {
    state.SkipWithError("shared data not found");
    return;
  }
  size_t boxes = 0;
  for (auto _ : state) {
    const DetectionTable table = load();
    for (int64_t f = 0; f < 100; ++f) {
      std::vector<beslam_box3d> out = table.at(f);  // what the plugin hands to the host
      boxes += out.size();
      benchmark::DoNotOptimize(out.data());
    }
  }
  // CPU time per replayed frame (parsing included), printed with its unit.
  state.counters["time_per_frame"] = benchmark::Counter(static_cast<double>(state.iterations()) * 100.0,
                                                        benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["boxes_per_frame"] = static_cast<double>(boxes) / (100.0 * static_cast<double>(state.iterations()));
}

void BM_ReplayFrame(benchmark::State& state) {
  if (!fs::exists(kRoot)) {
    state.SkipWithError("shared data not found");
    return;
  }
  const DetectionTable table = load();
  int64_t f = 0;
  for (auto _ : state) {
    std::vector<beslam_box3d> out = table.at(f);
    benchmark::DoNotOptimize(out.data());
    f = (f + 1) % 100;
  }
}

}  // namespace

BENCHMARK(BM_ReplayLoadAnd100Frames)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReplayFrame)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
