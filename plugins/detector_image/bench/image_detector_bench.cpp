// detector_image timing at KITTI size on one core (target: at most 25 ms per frame, detection + lifting).
//   build-det/bench/detector_image_bench --benchmark_repetitions=10 --benchmark_report_aggregates_only=true
// Uses KITTI 06 frame 20 and Yolo-Fastest from the shared folders; skips (with a message) when absent.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "beslam/detector_image/image_detector.hpp"

namespace {

using namespace beslam::detector_image;

const std::string kModelDir = std::string(BESLAM_SHARED_MODELS) + "/yolo-fastest-1.1";
const std::string kImage = std::string(BESLAM_SHARED_DATA) + "/kitti/odometry/sequences/06/image_0/000020.png";

const beslam_camera kCamera = {sizeof(beslam_camera), 1226, 370, 0, 707.0912, 707.0912, 601.8873, 183.1104};

void detectAndLift(benchmark::State& state) {
  cv::setNumThreads(1);
  if (!std::filesystem::exists(kModelDir + "/yolo-fastest-1.1.cfg") || !std::filesystem::exists(kImage)) {
    state.SkipWithError("shared model or KITTI 06 frame 20 absent");
    return;
  }
  DnnOptions options;
  options.model = kModelDir + "/yolo-fastest-1.1.cfg";
  options.weights = kModelDir + "/yolo-fastest-1.1.weights";
  options.input_width = static_cast<int>(state.range(0));
  options.input_height = static_cast<int>(state.range(1));
  Detector2D detector(options);
  const GroundLifter lifter(kCamera, LiftOptions{});
  const cv::Mat image = cv::imread(kImage, cv::IMREAD_GRAYSCALE);
  detector.detect(image);  // warm-up: first forward allocates
  size_t boxes = 0;
  for (auto _ : state) {
    for (const Detection2D& d : detector.detect(image)) {
      const beslam_box3d b = lifter.lift(d);
      benchmark::DoNotOptimize(b);
      ++boxes;
    }
  }
  state.counters["boxes_per_frame"] =
      benchmark::Counter(static_cast<double>(boxes), benchmark::Counter::kAvgIterations);
}
BENCHMARK(detectAndLift)
    ->Args({320, 320})
    ->Args({512, 160})
    ->Args({640, 192})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void liftOnly(benchmark::State& state) {
  const GroundLifter lifter(kCamera, LiftOptions{});
  const Detection2D d{BESLAM_CLASS_CAR, 0.7f, cv::Rect2d(746, 180, 123, 77)};
  for (auto _ : state) benchmark::DoNotOptimize(lifter.lift(d));
}
BENCHMARK(liftOnly)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
