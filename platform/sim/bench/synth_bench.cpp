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

// Renders every 37th frame of a preset round and round (frames differ, so no cache helps).
void renderFrames(benchmark::State& state, const char* preset, bool lidar) {
  const auto& s = synth(preset, lidar);
  int frame = 0;
  beslam::sim::FrameRender fr;
  for (auto _ : state) {
    s.render(frame, fr);
    benchmark::DoNotOptimize(fr.grey.data);
    benchmark::DoNotOptimize(fr.lidar.data());
    frame = (frame + 37) % s.frameCount();
  }
}

void BM_RenderFrameWithLidar(benchmark::State& state) { renderFrames(state, "urban_loop", true); }
BENCHMARK(BM_RenderFrameWithLidar)->Unit(benchmark::kMillisecond);

void BM_RenderFrameCameraOnly(benchmark::State& state) { renderFrames(state, "urban_loop", false); }
BENCHMARK(BM_RenderFrameCameraOnly)->Unit(benchmark::kMillisecond);

void BM_RenderFrameDynamicStreet(benchmark::State& state) { renderFrames(state, "dynamic_street", true); }
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
