// Trajectory files (KITTI poses, TUM rows): what `beslam eval` and the pose-replay backend read, and what
// a killed run leaves. Bad files are one beslam::Error naming the file (and line).
#include "beslam/formats/trajectory.hpp"

#include "beslam/formats/error.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "trajectory.txt");
  beslam::fuzz::acceptErrors([&] { beslam::formats::readKitti(path); });
  beslam::fuzz::acceptErrors([&] { beslam::formats::readTum(path); });
  beslam::fuzz::acceptErrors([&] { beslam::formats::read(path, beslam::formats::detectFormat(path)); });
  return 0;
}
