#include "scale/object_range.hpp"

#include <algorithm>
#include <cmath>

namespace beslam::orb {

std::optional<double> rayBoxEntry(const Eigen::Vector3d& ray_cam, const ObjectBox& box) {
  // Slab test in the box frame.
  const Eigen::Isometry3d T_box_cam = box.T_cam_box.inverse();
  const Eigen::Vector3d o = T_box_cam.translation(), d = T_box_cam.linear() * ray_cam;
  double t_in = 0, t_out = 1e18;
  for (int k = 0; k < 3; ++k) {
    const double half = box.size[k] / 2;
    if (std::abs(d[k]) < 1e-12) {
      if (std::abs(o[k]) > half) return std::nullopt;
      continue;
    }
    double t0 = (-half - o[k]) / d[k], t1 = (half - o[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
    if (t_in > t_out) return std::nullopt;
  }
  if (!(t_in > 0)) return std::nullopt;  // the camera is inside the box
  return t_in;
}

}  // namespace beslam::orb
