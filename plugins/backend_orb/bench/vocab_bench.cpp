// Google Benchmark: backend_orb's vocabulary. BM_VocabularyLoad reads the default vocabulary
// (plugins/backend_orb/data/orb_vocabulary.bvoc; target under 50 ms); BM_BowTransform2000 converts a
// 2000-feature frame (KITTI 00 frame 0 when the shared data is there, else a synthetic textured image)
// to its BoW vector and direct index (target under 1 ms). BESLAM_VOCABULARY=FILE benchmarks another file.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "features/orb_extractor.hpp"
#include "place/vocabulary.hpp"
#include "test_util.hpp"

namespace {

using beslam::orb::place::Vocabulary;

std::string vocabularyFile() {
  const char* env = std::getenv("BESLAM_VOCABULARY");
  return env ? env : BESLAM_SOURCE_DIR "/plugins/backend_orb/data/orb_vocabulary.bvoc";
}

cv::Mat frameDescriptors() {
  const std::string kitti = BESLAM_SHARED_DATA "/kitti/odometry/sequences/00/image_0/000000.png";
  cv::Mat image = cv::imread(kitti, cv::IMREAD_GRAYSCALE);
  if (image.empty()) image = beslam::orb::test::texturedImage(1241, 376, 5);
  beslam::orb::ExtractorOptions eo;
  eo.features = 2000;
  return beslam::orb::OrbExtractor(eo).extract(image, cv::Mat())->descriptors;
}

void BM_VocabularyLoad(benchmark::State& state) {
  const std::string file = vocabularyFile();
  if (!std::filesystem::exists(file)) {
    state.SkipWithError("no vocabulary file");
    return;
  }
  for (auto _ : state) {
    Vocabulary v = Vocabulary::load(file);
    benchmark::DoNotOptimize(v.numWords());
  }
}
BENCHMARK(BM_VocabularyLoad)->Unit(benchmark::kMillisecond);

void BM_BowTransform2000(benchmark::State& state) {
  const std::string file = vocabularyFile();
  if (!std::filesystem::exists(file)) {
    state.SkipWithError("no vocabulary file");
    return;
  }
  const Vocabulary v = Vocabulary::load(file);
  const cv::Mat descriptors = frameDescriptors();
  beslam::orb::place::BowVector bow;
  beslam::orb::place::FeatureVector fv;
  for (auto _ : state) {
    v.transform(descriptors, bow, &fv, 4);
    benchmark::DoNotOptimize(bow.data());
  }
  state.counters["features"] = descriptors.rows;
  state.counters["words"] = static_cast<double>(bow.size());
}
BENCHMARK(BM_BowTransform2000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
