// Similarity transforms for loop closure: Sim3 (x -> s R x + t), its composition and inverse, the
// closed-form alignment of matched 3D points (Umeyama; scale fixed to 1 for a metric map) and a seeded
// RANSAC over 3D-3D matches whose inliers are judged, as ORB-SLAM2 does, by the reprojection error of
// each transformed point in the other keyframe's image (chi-square 9.21 at the keypoint's scale).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <vector>

namespace beslam::orb::loop {

struct Sim3 {
  double s = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  static Sim3 fromIsometry(const Eigen::Isometry3d& T, double s = 1.0) { return {s, T.linear(), T.translation()}; }
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return s * (R * p) + t; }
  Sim3 operator*(const Sim3& o) const { return {s * o.s, R * o.R, s * (R * o.t) + t}; }
  Sim3 inverse() const { return {1.0 / s, R.transpose(), -(R.transpose() * t) / s}; }
  // The rigid part with the translation divided by the scale (a camera pose from a Sim3 world->camera).
  Eigen::Isometry3d toIsometry() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() = t / s;
    return T;
  }
};

// The Sim3 S minimising sum |p_b - S p_a|^2 over matched points (columns), or nothing when the points are
// degenerate (fewer than 3, or collinear). fix_scale: s = 1 (SE3).
std::optional<Sim3> alignPoints(const std::vector<Eigen::Vector3d>& p_a, const std::vector<Eigen::Vector3d>& p_b,
                                bool fix_scale);

// One 3D-3D match between keyframes 1 and 2: the point in each camera's frame and its keypoint
// (pixel) and pyramid-level variance in each image.
struct PointMatch {
  Eigen::Vector3d p_c1, p_c2;
  Eigen::Vector2d uv1, uv2;
  double sigma2_1 = 1.0, sigma2_2 = 1.0;
};

struct PinholeIntrinsics {
  double fx = 1, fy = 1, cx = 0, cy = 0;
  Eigen::Vector2d project(const Eigen::Vector3d& p) const { return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy}; }
};

struct Sim3RansacOptions {
  double probability = 0.99;
  int min_inliers = 20;
  int max_iterations = 300;
  bool fix_scale = false;
  uint64_t seed = 1;
};

struct Sim3RansacResult {
  Sim3 S_21;                  // maps points of camera 1 into camera 2
  std::vector<bool> inliers;  // per match
  int inlier_count = 0;
};

// RANSAC over minimal sets of 3 matches; the best model by inlier count is refit on its inliers.
// Nothing when no model reaches min_inliers.
std::optional<Sim3RansacResult> ransacSim3(const std::vector<PointMatch>& matches, const PinholeIntrinsics& camera,
                                           const Sim3RansacOptions& options);

// Inliers of S_21 among matches (both reprojections within chi-square 9.21 x sigma^2, points in front).
std::vector<bool> sim3Inliers(const Sim3& S_21, const std::vector<PointMatch>& matches, const PinholeIntrinsics& camera,
                              int* count);

}  // namespace beslam::orb::loop
