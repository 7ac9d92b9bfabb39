#include "beslam/formats/velodyne.hpp"

#include <cstring>
#include <filesystem>

#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"

namespace beslam::formats {

static_assert(sizeof(float) == 4, "KITTI scans are float32");

std::vector<float> readVelodyneBin(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throwAt(path, "missing LiDAR scan");
  const std::string bytes = readFile(path);
  if (bytes.size() % 16 != 0)
    throwAt(path, "truncated LiDAR scan (" + std::to_string(bytes.size()) +
                      " bytes, not a multiple of 16 = 4 float32 x y z r)");
  std::vector<float> xyzr(bytes.size() / sizeof(float));
  if (!bytes.empty()) std::memcpy(xyzr.data(), bytes.data(), bytes.size());
  return xyzr;
}

void writeVelodyneBin(const std::string& path, const std::vector<float>& xyzr) {
  if (xyzr.size() % 4 != 0) throwAt(path, "point buffer size is not a multiple of 4 (x y z r)");
  writeFileAtomic(path, std::string(reinterpret_cast<const char*>(xyzr.data()), xyzr.size() * sizeof(float)));
}

}  // namespace beslam::formats
