// KITTI object and tracking label rows (also the detection rows replay reads): bad rows are one
// beslam::Error naming the line, good rows parse to finite numbers.
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/datasets/labels.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  int line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    beslam::fuzz::acceptErrors([&] { (void)beslam::datasets::parseTrackingRow(line, "fuzz.txt", line_no); });
    beslam::fuzz::acceptErrors([&] { (void)beslam::datasets::parseObjectRow(line, "fuzz.txt", line_no); });
  }
  return 0;
}
