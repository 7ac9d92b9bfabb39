// Helpers shared by the eval tests: the scratch-folder fixture and a synthetic trajectory with known poses.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "beslam/test/scratch_dir.hpp"
#include "beslam/trajectory/trajectory.hpp"

namespace beslam::eval::test {

using beslam::test::ScratchDir;

// A helix with a wobbling orientation: T_world_cam(i), stamps 10 Hz from `t0`.
inline trajectory::Trajectory helix(int n, double t0 = 100.0) {
  trajectory::Trajectory trajectory;
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
    T_world_cam.linear() = (Eigen::AngleAxisd(0.08 * i, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.2 * std::sin(0.3 * i), Eigen::Vector3d::UnitX()) *
                            Eigen::AngleAxisd(0.1 * std::cos(0.2 * i), Eigen::Vector3d::UnitY()))
                               .toRotationMatrix();
    T_world_cam.translation() = Eigen::Vector3d(4.0 * std::cos(0.08 * i), 4.0 * std::sin(0.08 * i), 0.05 * i);
    trajectory.push_back(t0 + 0.1 * i, T_world_cam);
  }
  return trajectory;
}

// Shared data folder of the evo reference trajectories ("" when absent).
inline std::string evoDataDir() {
  const std::filesystem::path dir = std::filesystem::path(BESLAM_SHARED_DATA) / "evo";
  return std::filesystem::exists(dir / "KITTI_00_gt.txt") ? dir.string() : std::string();
}

}  // namespace beslam::eval::test
