// KITTI calibration files (odometry and object layouts): bad files are one beslam::Error.
#include "beslam/common/error.hpp"
#include "beslam/datasets/kitti_calib.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "calib.txt");
  beslam::fuzz::acceptErrors([&] { beslam::datasets::readOdometryCalib(path); });
  beslam::fuzz::acceptErrors([&] { beslam::datasets::readObjectCalib(path); });
  return 0;
}
