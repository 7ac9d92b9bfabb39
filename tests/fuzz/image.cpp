// The image checks that catch truncated or corrupt files before OpenCV decodes them: the PNG chunk walk
// on raw bytes, and loadImage on the file (PNG or JPEG by signature). Bad input is one beslam::Error.
#include "beslam/common/error.hpp"
#include "beslam/datasets/image_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  beslam::fuzz::acceptErrors([&] { beslam::datasets::checkPng("fuzz.png", bytes); });
  const bool jpeg = size >= 2 && data[0] == 0xFF && data[1] == 0xD8;
  const std::string path = beslam::fuzz::writeScratch(data, size, jpeg ? "image.jpg" : "image.png");
  beslam::fuzz::acceptErrors([&] { beslam::datasets::loadImage(path, true); });
  return 0;
}
