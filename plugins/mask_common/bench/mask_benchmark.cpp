// Google Benchmark of the mask generators at KITTI size (1241 x 376), one core:
//   BoxProjection/20:        20 boxes, mask_box without contours (target <= 5 ms per frame)
//   BoxContour/10:           10 objects, mask_box with contours
//   LidarContour/10:         10 objects, mask_lidar with BEV refinement, point masks and contours
//                            (target <= 15 ms per frame), scan of the synthetic street (64 beams)
// Run: build/bin/mask_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include "beslam/mask_common/mask_builder.hpp"
#include "synthetic_scene.hpp"

using namespace beslam;
using namespace beslam::mask;

namespace {

// n cars parked along both sides and ahead, 6 to 30 m away, rendered with a 64-beam scan.
fixture::Scene scene(int n) {
  fixture::Scene s;
  s.K = fixture::kittiIntrinsics();
  for (int i = 0; i < n; ++i) {
    const double side = (i % 3 == 0) ? 0.0 : (i % 3 == 1 ? -3.8 : 3.8);
    const double z = 6 + (i / 3) * 24.0 / std::max(1, (n - 1) / 3) + (i % 3) * 1.3;
    s.cars.push_back(fixture::makeCar(i + 1, side, z, M_PI / 2, 4.2, 1.75, 1.5, 80 + 15 * (i % 8),
                                      i % 2 ? BESLAM_MOTION_STATIC : BESLAM_MOTION_DYNAMIC));
  }
  fixture::render(s, 3);
  fixture::scan(s, 1.65, 0.08);  // KITTI-like horizontal resolution
  return s;
}

void run(benchmark::State& state, MaskOptions o) {
  static const fixture::Scene s20 = scene(20), s10 = scene(10);
  const fixture::Scene& s = state.range(0) == 20 ? s20 : s10;
  std::vector<beslam_box3d> boxes;
  for (const auto& c : s.cars) boxes.push_back(c.box);
  beslam_point_cloud_view view{};
  view.data = s.lidar.data(), view.count = s.lidar.size() / 4, view.stride_bytes = 16;
  const MaskBuilder builder(s.K, s.T_cam_lidar, o);
  cv::Mat mask(s.gray.size(), CV_16UC1);
  for (auto _ : state) {
    mask.setTo(0);
    builder.generate(s.gray, view, boxes, mask);
    benchmark::DoNotOptimize(mask.data);
  }
  state.counters["points"] = static_cast<double>(view.count);
}

void BoxProjection(benchmark::State& state) {
  MaskOptions o;
  o.contour = false;
  run(state, o);
}
void BoxContour(benchmark::State& state) {
  MaskOptions o;
  o.contour = true;
  run(state, o);
}
void LidarContour(benchmark::State& state) {
  MaskOptions o;
  o.use_lidar = true, o.contour = true;
  run(state, o);
}

}  // namespace

BENCHMARK(BoxProjection)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BoxContour)->Arg(10)->Unit(benchmark::kMillisecond);
BENCHMARK(LidarContour)->Arg(10)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
