// Minimal KITTI odometry reading for this module's tool and tests: P0 intrinsics from calib.txt (rows
// with or without the "P0:" name), image_0/NNNNNN.png, times.txt; KITTI pose rows (3 x 4, camera to world) come from
// the SDK's formats.
#pragma once

#include <Eigen/Geometry>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "beslam/formats/trajectory.hpp"
#include "beslam_orb/orb_slam.hpp"

namespace beslam::orb::kitti {

inline Camera readCamera(const std::string& calib_path, int width, int height) {
  std::ifstream in(calib_path);
  if (!in) throw std::runtime_error(calib_path + ": cannot open");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string first;
    if (!(ss >> first)) continue;
    std::vector<double> v;
    if (first.back() == ':') {
      if (first != "P0:") continue;
    } else {
      v.push_back(std::stod(first));
    }
    double x;
    while (ss >> x) v.push_back(x);
    if (v.size() != 12) throw std::runtime_error(calib_path + ": P0 needs 12 numbers");
    Camera c;
    c.width = width;
    c.height = height;
    c.fx = v[0];
    c.cx = v[2];
    c.fy = v[5];
    c.cy = v[6];
    return c;  // the first row is P0 in both layouts
  }
  throw std::runtime_error(calib_path + ": no P0 row");
}

// KITTI pose rows through the SDK's formats (beslam::Error "file:line: cause" on a bad row).
inline std::vector<Eigen::Isometry3d> readPoses(const std::string& path) {
  const formats::Trajectory trajectory = formats::readKitti(path);
  return {trajectory.poses.begin(), trajectory.poses.end()};
}

inline std::vector<double> readTimes(const std::string& path) {
  std::ifstream in(path);
  std::vector<double> t;
  double x;
  while (in >> x) t.push_back(x);
  return t;
}

inline std::string imagePath(const std::string& seq_dir, size_t i) {
  char name[32];
  std::snprintf(name, sizeof(name), "image_0/%06zu.png", i);
  return seq_dir + "/" + name;
}

inline void writePose(std::ostream& out, const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d& R = T.linear();
  const Eigen::Vector3d& t = T.translation();
  out << R(0, 0) << ' ' << R(0, 1) << ' ' << R(0, 2) << ' ' << t.x() << ' ' << R(1, 0) << ' ' << R(1, 1) << ' '
      << R(1, 2) << ' ' << t.y() << ' ' << R(2, 0) << ' ' << R(2, 1) << ' ' << R(2, 2) << ' ' << t.z() << '\n';
}

}  // namespace beslam::orb::kitti
