// Rendering speed: one 1241 x 376 frame (camera, mask, labels and a 64-beam LiDAR scan) on one core.
// Target: at most 50 ms median. Run with --benchmark_repetitions=5 for the median.
#include <benchmark/benchmark.h>

#include "beslam/sim/synth.hpp"

namespace {

const beslam::sim::Synthesizer& synth(const char* preset, bool lidar) {
  static std::unique_ptr<beslam::sim::Synthesizer> with, without, dyn;
  auto& slot = std::string(preset) == "dynamic_street" ? dyn : (lidar ? with : without);
  if (!slot) {
    auto c = beslam::sim::presetConfig(preset);
    c.lidar.enabled = lidar;
    slot = std::make_unique<beslam::sim::Synthesizer>(c);
  }
  return *slot;
}

void BM_RenderFrameWithLidar(benchmark::State& state) {
  const auto& s = synth("urban_loop", true);
  int frame = 0;
  beslam::sim::FrameRender fr;
  for (auto _ : state) {
    s.render(frame, fr);
    benchmark::DoNotOptimize(fr.lidar.data());
    frame = (frame + 37) % s.frameCount();
  }
}
BENCHMARK(BM_RenderFrameWithLidar)->Unit(benchmark::kMillisecond);

void BM_RenderFrameCameraOnly(benchmark::State& state) {
  const auto& s = synth("urban_loop", false);
  int frame = 0;
  beslam::sim::FrameRender fr;
  for (auto _ : state) {
    s.render(frame, fr);
    benchmark::DoNotOptimize(fr.grey.data);
    frame = (frame + 37) % s.frameCount();
  }
}
BENCHMARK(BM_RenderFrameCameraOnly)->Unit(benchmark::kMillisecond);

void BM_RenderFrameDynamicStreet(benchmark::State& state) {
  const auto& s = synth("dynamic_street", true);
  int frame = 0;
  beslam::sim::FrameRender fr;
  for (auto _ : state) {
    s.render(frame, fr);
    benchmark::DoNotOptimize(fr.lidar.data());
    frame = (frame + 37) % s.frameCount();
  }
}
BENCHMARK(BM_RenderFrameDynamicStreet)->Unit(benchmark::kMillisecond);

void BM_BuildWorld(benchmark::State& state) {
  const auto c = beslam::sim::presetConfig("urban_loop");
  for (auto _ : state) {
    beslam::sim::Synthesizer s(c);
    benchmark::DoNotOptimize(&s);
  }
}
BENCHMARK(BM_BuildWorld)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
