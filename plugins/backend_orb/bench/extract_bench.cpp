// Google Benchmark: backend_orb's ORB extraction, the largest per-frame cost of a run
// (docs/performance.md). A KITTI 00 frame when the shared data is there, else a synthetic textured
// image of KITTI's size; the label mask is the demo's kind: a moving car's box (label 1, no features) and
// two parked cars' boxes (labels >= 1000, their own FAST threshold and budget share).
//   BM_Prepare:          the label-independent part (pyramids, FAST), on the runner's producer thread
//   BM_ExtractPrepared:  the rest (masked corners, quadtree, orientation, rBRIEF), on the main thread
//   BM_ExtractNoLabels:  a whole extraction without a mask (what a frame costs without semantics)
#include <benchmark/benchmark.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "features/orb_extractor.hpp"
#include "test_util.hpp"

namespace {

using beslam::orb::OrbExtractor;

cv::Mat benchImage() {
  const std::string kitti = BESLAM_SHARED_DATA "/kitti/odometry/sequences/00/image_0/000000.png";
  cv::Mat image = cv::imread(kitti, cv::IMREAD_GRAYSCALE);
  if (image.empty()) image = beslam::orb::test::texturedImage(1241, 376, 5);
  return image;
}

cv::Mat demoLabels(const cv::Size& size) {
  cv::Mat labels(size, CV_16UC1, cv::Scalar(0));
  labels(cv::Rect(560, 160, 140, 90)).setTo(1);     // a moving car ahead
  labels(cv::Rect(90, 170, 330, 140)).setTo(1000);  // parked cars on either side
  labels(cv::Rect(840, 165, 300, 130)).setTo(1001);
  return labels;
}

beslam::orb::ExtractorOptions options() {
  beslam::orb::ExtractorOptions eo;
  eo.features = 3000;  // the demo's budget
  return eo;
}

void BM_Prepare(benchmark::State& state) {
  const cv::Mat image = benchImage();
  const OrbExtractor extractor(options());
  for (auto _ : state) benchmark::DoNotOptimize(extractor.prepare(image).get());
}
BENCHMARK(BM_Prepare)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ExtractPrepared(benchmark::State& state) {
  const cv::Mat image = benchImage();
  const cv::Mat labels = demoLabels(image.size());
  const OrbExtractor extractor(options());
  const auto prepared = extractor.prepare(image);
  for (auto _ : state) benchmark::DoNotOptimize(extractor.extract(image, labels, 0, prepared.get()).get());
}
BENCHMARK(BM_ExtractPrepared)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ExtractNoLabels(benchmark::State& state) {
  const cv::Mat image = benchImage();
  const OrbExtractor extractor(options());
  for (auto _ : state) benchmark::DoNotOptimize(extractor.extract(image, cv::Mat()).get());
}
BENCHMARK(BM_ExtractNoLabels)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
