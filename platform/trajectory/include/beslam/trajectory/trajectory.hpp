// Trajectories: timestamped camera poses T_world_cam, and their KITTI / TUM file formats.
// KITTI format: one row per pose, the top 3x4 of T_world_cam row-major (12 numbers), no timestamps
// (stamps become 0, 1, 2, ... unless given). TUM format: "t x y z qx qy qz qw" per row, '#' comments.
// Readers throw beslam::Error naming file and line on a malformed row or a non-finite value;
// writers replace the file atomically (full double precision).
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace beslam::trajectory {

struct Trajectory {
  std::vector<double> stamps;                                             // seconds
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

// Format by name: "kitti" or "tum"; throws beslam::Error on any other name.
Trajectory read(const std::string& path, const std::string& format);

}  // namespace beslam::trajectory
