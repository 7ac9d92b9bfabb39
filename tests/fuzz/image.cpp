// The image checks that catch truncated or corrupt files before OpenCV decodes them: the PNG chunk walk
// on raw bytes, and loadImage on the file (PNG or JPEG by signature). Bad input is one beslam::Error.
// The seed corpus is written by this binary (run_fuzzer.sh asks for it): BESLAM_FUZZ_WRITE_SEEDS=DIR image.
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "beslam/common/error.hpp"
#include "beslam/datasets/image_io.hpp"
#include "fuzz_support.hpp"

namespace {

// Small images of every kind the readers take: 8-bit grey, colour (PNG and JPEG), 16-bit depth; seeded noise.
void writeSeeds(const std::string& dir) {
  cv::RNG rng(1);
  cv::Mat grey(8, 8, CV_8UC1), colour(6, 10, CV_8UC3), depth(4, 4, CV_16UC1);
  rng.fill(grey, cv::RNG::UNIFORM, 0, 256);
  rng.fill(colour, cv::RNG::UNIFORM, 0, 256);
  rng.fill(depth, cv::RNG::UNIFORM, 0, 65536);
  cv::imwrite(dir + "/grey.png", grey);
  cv::imwrite(dir + "/colour.png", colour);
  cv::imwrite(dir + "/colour.jpg", colour);
  cv::imwrite(dir + "/depth16.png", depth);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) { return beslam::fuzz::writeSeedsIfAsked(writeSeeds); }

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  beslam::fuzz::acceptErrors([&] { beslam::datasets::checkPng("fuzz.png", bytes); });
  const bool jpeg = size >= 2 && data[0] == 0xFF && data[1] == 0xD8;
  const std::string path = beslam::fuzz::writeScratch(data, size, jpeg ? "image.jpg" : "image.png");
  beslam::fuzz::acceptErrors([&] { beslam::datasets::loadImage(path, true); });
  return 0;
}
