// Trajectories: timestamped camera poses T_world_cam, and their KITTI / TUM file formats.
// KITTI format: one row per pose, the top 3x4 of T_world_cam row-major (12 numbers), no timestamps
// (stamps become 0, 1, 2, ... unless given). TUM format: "t x y z qx qy qz qw" per row, '#' comments.
// Readers throw beslam::Error (beslam/formats/error.hpp) naming file and line on a malformed row or a non-finite value;
// writers replace the file atomically (full double precision).
//
// Details of the contract:
// - Both readers skip blank lines and lines starting with '#'; numbers may be separated by spaces, tabs
//   or commas; CRLF line ends are accepted. A file with no pose at all is an error (names the file).
// - KITTI rotations are kept exactly as written (not re-orthonormalised, as evo does), but a rotation
//   part that is clearly not a rotation (|R^T R - I| > 1e-3 or det(R) <= 0) is rejected.
// - TUM quaternions are normalised on read; a (near-)zero quaternion is rejected.
// - Writers print the shortest decimal form that reads back to the identical double.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace beslam::formats {

struct Trajectory {
  std::vector<double> stamps;                                                         // seconds
  std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>> poses;  // T_world_cam
  std::size_t size() const { return poses.size(); }
  bool empty() const { return poses.empty(); }
  void push_back(double stamp, const Eigen::Isometry3d& T_world_cam) {
    stamps.push_back(stamp);
    poses.push_back(T_world_cam);
  }
};

Trajectory readKitti(const std::string& path);
Trajectory readTum(const std::string& path);
void writeKitti(const std::string& path, const Trajectory& trajectory);
void writeTum(const std::string& path, const Trajectory& trajectory);

// One row of each format, as the writers print it (with its line end), for files written row by row;
// a TUM file starts with kTumHeader.
std::string kittiRow(const Eigen::Isometry3d& T_world_cam);
std::string tumRow(double stamp, const Eigen::Isometry3d& T_world_cam);
inline constexpr const char* kTumHeader = "# timestamp tx ty tz qx qy qz qw\n";

// Format by name: "kitti" or "tum"; throws beslam::Error on any other name.
Trajectory read(const std::string& path, const std::string& format);

// "kitti" or "tum", from the number of columns (12 or 8) of the first data row of the file.
// Throws beslam::Error naming the file (and line) when it is missing, empty or has another column count.
std::string detectFormat(const std::string& path);

}  // namespace beslam::formats
