// KITTI Velodyne scans: little-endian float32 records "x y z reflectance", in the LiDAR frame
// (x forward, y left, z up, metres). A file whose size is not a multiple of 16 bytes is "truncated".
#pragma once

#include <string>
#include <vector>

namespace beslam::formats {

// Returns x y z r interleaved (size = 4 * points); throws beslam::Error naming the file when it is missing,
// unreadable or truncated.
std::vector<float> readVelodyneBin(const std::string& path);

// Writes the same format (tests, tools); throws beslam::Error when xyzr.size() is not a multiple of 4.
void writeVelodyneBin(const std::string& path, const std::vector<float>& xyzr);

}  // namespace beslam::formats
