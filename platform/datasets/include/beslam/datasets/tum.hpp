// TUM RGB-D helpers: the published Kinect colour-camera intrinsics of the fr1/fr2/fr3 recordings (TUM has
// no calibration file in a sequence folder) and ground-truth association by timestamp.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "beslam/datasets/dataset.hpp"
#include "beslam/trajectory/trajectory.hpp"

namespace beslam::datasets {

struct TumIntrinsics {
  std::string name;                  // "fr1", "fr2", "fr3"
  Camera camera;                     // 640x480
  std::array<double, 5> distortion;  // OpenCV order k1 k2 p1 p2 k3 (zero for fr3: its images are undistorted)
};

// The defaults for a sequence folder whose name contains "freiburg1"/"fr1", "freiburg2"/"fr2" or
// "freiburg3"/"fr3"; nullopt otherwise.
std::optional<TumIntrinsics> tumDefaultIntrinsics(const std::string& folder_name);

// Pose at `stamp` from a time-sorted trajectory: interpolated (linear / slerp) between the samples that
// bracket it when they are at most max_gap apart, else the nearest sample within max_dt, else nullopt.
std::optional<Eigen::Isometry3d> poseAt(const trajectory::Trajectory& trajectory, double stamp, double max_dt,
                                        double max_gap = 0.1);

}  // namespace beslam::datasets
