// Pinhole projection helpers on the public Camera.
#pragma once

#include <Eigen/Core>

#include "beslam_orb/options.hpp"

namespace beslam::orb {

inline Eigen::Vector2d project(const Camera& c, const Eigen::Vector3d& p_cam) {
  const double iz = 1.0 / p_cam.z();
  return {c.fx * p_cam.x() * iz + c.cx, c.fy * p_cam.y() * iz + c.cy};
}

inline Eigen::Vector3d unproject(const Camera& c, double u, double v) {  // ray with z = 1
  return {(u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0};
}

inline bool inImage(const Camera& c, double u, double v) { return u >= 0 && v >= 0 && u < c.width && v < c.height; }

inline Eigen::Matrix3d intrinsics(const Camera& c) {
  Eigen::Matrix3d K;
  K << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1;
  return K;
}

}  // namespace beslam::orb
