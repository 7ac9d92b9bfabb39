// GroundLifter: a class-size prior placed on a flat road so that its projection matches the 2D box.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "beslam/detector_image/image_detector.hpp"

namespace beslam::detector_image {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Relative spread of a class's true height about its prior (cars 1.4-1.7 m about 1.5 m): the distance error
// of a box placed by its pixel height.
constexpr double kClassHeightSpread = 0.1;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("detector_image: " + what);
}

// The level frame shares the camera's origin and x axis, its y axis is the true vertical (down).
// p_cam = Rx(pitch) * p_level.
struct Geometry {
  double fx, fy, cx, cy, c, s, H;
  Eigen::Vector3d toCam(const Eigen::Vector3d& p) const {
    return {p.x(), c * p.y() - s * p.z(), s * p.y() + c * p.z()};
  }
  Eigen::Vector3d toLevel(const Eigen::Vector3d& p) const {
    return {p.x(), c * p.y() + s * p.z(), -s * p.y() + c * p.z()};
  }
};

struct Projected {
  double u0, v0, u1, v1;
  bool valid;
};

// 2D box of a box standing on the road at (X, Z) of the level frame, size (l, w, h), yaw about the vertical.
Projected project(const Geometry& g, double X, double Z, double yaw, const std::array<double, 3>& size) {
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  Projected p{1e18, 1e18, -1e18, -1e18, true};
  for (int i = 0; i < 8; ++i) {
    const double a = (i & 1 ? 0.5 : -0.5) * size[0], b = (i & 2 ? 0.5 : -0.5) * size[1];
    const double y = g.H - (i & 4 ? size[2] : 0.0);
    // Box x along the heading (cos yaw, 0, -sin yaw), box z across it (sin yaw, 0, cos yaw): KITTI rotation_y.
    const Eigen::Vector3d q = g.toCam({X + a * cy + b * sy, y, Z - a * sy + b * cy});
    if (q.z() < 0.1) {
      p.valid = false;
      return p;
    }
    const double u = g.fx * q.x() / q.z() + g.cx, v = g.fy * q.y() / q.z() + g.cy;
    p.u0 = std::min(p.u0, u), p.u1 = std::max(p.u1, u), p.v0 = std::min(p.v0, v), p.v1 = std::max(p.v1, v);
  }
  return p;
}

enum class UEdge { Center, Left, Right };
enum class VEdge { Bottom, Top };

double uOf(const Projected& p, UEdge e) {
  return e == UEdge::Left ? p.u0 : e == UEdge::Right ? p.u1 : 0.5 * (p.u0 + p.u1);
}
double vOf(const Projected& p, VEdge e) { return e == VEdge::Bottom ? p.v1 : p.v0; }

struct Fit {
  double X = 0, Z = 0;
  bool ok = false;
  double dv_dZ = 0;  // sensitivity of the vertical constraint to distance
  Projected proj{};
};

// Newton on (X, Z) so that the chosen horizontal and vertical edges land on (u_target, v_target).
Fit solvePosition(const Geometry& g, double yaw, const std::array<double, 3>& size, UEdge ue, VEdge ve, double u_target,
                  double v_target, double X0, double Z0) {
  Fit f;
  double X = X0, Z = std::max(Z0, 1.0);
  for (int it = 0; it < 20; ++it) {
    const Projected p = project(g, X, Z, yaw, size);
    if (!p.valid) {
      Z *= 1.5;
      continue;
    }
    const double ru = uOf(p, ue) - u_target, rv = vOf(p, ve) - v_target;
    const double hX = 1e-3 * std::max(1.0, Z), hZ = 1e-3 * std::max(1.0, Z);
    const Projected px = project(g, X + hX, Z, yaw, size), pz = project(g, X, Z + hZ, yaw, size);
    if (!px.valid || !pz.valid) {
      Z *= 1.5;
      continue;
    }
    const double a = (uOf(px, ue) - uOf(p, ue)) / hX, b = (uOf(pz, ue) - uOf(p, ue)) / hZ;
    const double c = (vOf(px, ve) - vOf(p, ve)) / hX, d = (vOf(pz, ve) - vOf(p, ve)) / hZ;
    const double det = a * d - b * c;
    if (std::abs(det) < 1e-12) break;
    double dX = -(d * ru - b * rv) / det, dZ = -(-c * ru + a * rv) / det;
    const double limit = 0.5 * Z;  // damp steps towards or away from the camera
    const double scale = std::max(std::abs(dZ) / limit, 1.0);
    dX /= scale, dZ /= scale;
    X += dX, Z += dZ;
    if (Z < 0.5) Z = 0.5;
    f.dv_dZ = d;
    if (std::abs(ru) < 0.05 && std::abs(rv) < 0.05) {
      f.ok = true;
      break;
    }
  }
  f.X = X, f.Z = Z;
  f.proj = project(g, X, Z, yaw, size);
  if (!f.proj.valid) f.ok = false;
  if (f.ok) {
    const Projected pz = project(g, X, Z + 1e-3 * Z, yaw, size);
    if (pz.valid) f.dv_dZ = (vOf(pz, ve) - vOf(f.proj, ve)) / (1e-3 * Z);
  }
  return f;
}

double angleDiffHalfTurn(double a, double b) {  // distance between two headings modulo pi
  double d = std::fmod(a - b, kPi);
  if (d < 0) d += kPi;
  return std::min(d, kPi - d);
}

}  // namespace

void LiftOptions::validate() const {
  require(camera_height > 0.1 && camera_height < 10, "camera_height must be in (0.1, 10) m");
  require(std::abs(camera_pitch) < 0.5, "camera_pitch must be within +-0.5 rad");
  require(max_distance > 0, "max_distance must be > 0");
  require(max_relative_uncertainty > 0, "max_relative_uncertainty must be > 0");
  require(pixel_sigma >= 0 && pitch_sigma >= 0 && border_px >= 0, "pixel_sigma, pitch_sigma, border_px must be >= 0");
  for (const auto* s : {&car_size, &pedestrian_size, &cyclist_size})
    require((*s)[0] > 0 && (*s)[1] > 0 && (*s)[2] > 0, "size priors must be positive");
  require(yaw_candidates >= 1 && yaw_candidates <= 360, "yaw_candidates must be in [1, 360]");
  require(yaw_prior_sigma > 0, "yaw_prior_sigma must be > 0");
  require(height_consistency > 1, "height_consistency must be > 1");
}

GroundLifter::GroundLifter(const beslam_camera& camera, const LiftOptions& options)
    : camera_(camera), options_(options) {
  options_.validate();
  require(camera_.fx > 0 && camera_.fy > 0 && camera_.width > 0 && camera_.height > 0,
          "the camera intrinsics are missing (fx, fy, width, height must be positive)");
}

beslam_box3d GroundLifter::lift(const Detection2D& d) const {
  const LiftOptions& o = options_;
  const Geometry g{
      camera_.fx,     camera_.fy, camera_.cx, camera_.cy, std::cos(o.camera_pitch), std::sin(o.camera_pitch),
      o.camera_height};
  const std::array<double, 3>& size = d.class_id == BESLAM_CLASS_PEDESTRIAN ? o.pedestrian_size
                                      : d.class_id == BESLAM_CLASS_CYCLIST  ? o.cyclist_size
                                                                            : o.car_size;
  const double x1 = d.box.x, y1 = d.box.y, x2 = d.box.x + d.box.width, y2 = d.box.y + d.box.height;
  const bool cut_left = x1 <= o.border_px, cut_right = x2 >= camera_.width - o.border_px;
  const bool cut_bottom = y2 >= camera_.height - o.border_px, cut_top = y1 <= o.border_px;
  const UEdge ue = cut_left && !cut_right ? UEdge::Right : cut_right && !cut_left ? UEdge::Left : UEdge::Center;
  const VEdge ve = cut_bottom && !cut_top ? VEdge::Top : VEdge::Bottom;
  const double u_target = ue == UEdge::Left ? x1 : ue == UEdge::Right ? x2 : 0.5 * (x1 + x2);
  const double v_target = ve == VEdge::Top ? y1 : y2;
  bool uncertain = cut_left || cut_right || cut_bottom;

  // Start: the road point under the bottom-centre pixel, or the height prior when that ray misses the road.
  const Eigen::Vector3d ray_level = g.toLevel({(0.5 * (x1 + x2) - g.cx) / g.fx, (y2 - g.cy) / g.fy, 1.0});
  double X0, Z0;
  if (ray_level.y() > 1e-3 && !cut_bottom) {
    const double t = o.camera_height / ray_level.y();
    X0 = t * ray_level.x(), Z0 = t * ray_level.z();
  } else {
    Z0 = g.fy * size[2] / std::max(y2 - y1, 1.0);
    X0 = Z0 * (0.5 * (x1 + x2) - g.cx) / g.fx;
    uncertain = true;
  }

  // Heading: road-aligned (yaw -pi/2) for pedestrians; else the candidate whose projected width fits best.
  const double road_yaw = -kPi / 2;
  const bool search_yaw = d.class_id != BESLAM_CLASS_PEDESTRIAN && o.yaw_candidates > 1 && !cut_left && !cut_right;
  const int candidates = search_yaw ? o.yaw_candidates : 1;
  Fit best;
  double best_yaw = road_yaw, best_cost = std::numeric_limits<double>::infinity();
  const double width_obs = std::max(x2 - x1, 1.0);
  for (int k = 0; k < candidates; ++k) {
    const double yaw = road_yaw + (search_yaw ? k * kPi / candidates : 0.0);
    const Fit f = solvePosition(g, yaw, size, ue, ve, u_target, v_target, X0, Z0);
    if (!f.ok) continue;
    const double width_err = ((f.proj.u1 - f.proj.u0) - width_obs) / width_obs;
    const double yaw_err = angleDiffHalfTurn(yaw, road_yaw) / o.yaw_prior_sigma;
    const double cost = width_err * width_err / (0.1 * 0.1) + yaw_err * yaw_err;
    if (cost < best_cost) best_cost = cost, best = f, best_yaw = yaw;
  }
  // Distance from the class height alone: a bottom edge at or near the horizon puts the road contact far
  // beyond it (a bad box, a sloped road); then the height prior places the box, flagged.
  const double z_height = g.fy * size[2] / std::max(y2 - y1, 1.0);
  if (best.ok && !cut_top && !cut_bottom && best.Z > o.height_consistency * z_height) best.ok = false;
  if (!best.ok) {
    best.Z = std::min(Z0, z_height);
    best.X = best.Z * (0.5 * (x1 + x2) - g.cx) / g.fx;
    best.dv_dZ = 0;
    uncertain = true;
  }

  beslam_box3d box{};
  box.class_id = d.class_id;
  box.track_id = -1;
  box.motion_state = BESLAM_MOTION_UNKNOWN;
  const Eigen::Vector3d center = g.toCam({best.X, o.camera_height - size[2] / 2, best.Z});
  for (int k = 0; k < 3; ++k) box.center_cam[k] = center[k];
  box.size[0] = size[0], box.size[1] = size[1], box.size[2] = size[2];
  box.yaw = best_yaw;
  box.score = d.score;
  box.flags = BESLAM_BOX_HAS_BBOX2D;
  box.bbox2d[0] = x1, box.bbox2d[1] = y1, box.bbox2d[2] = x2, box.bbox2d[3] = y2;
  box.truncation = static_cast<float>(cut_left || cut_right || cut_bottom ? 0.5 : 0.0);

  const double distance = center.norm();
  const double sigma_v = std::hypot(o.pixel_sigma, g.fy * o.pitch_sigma);
  const double sigma_z =
      std::abs(best.dv_dZ) > 1e-9 ? sigma_v / std::abs(best.dv_dZ) : std::numeric_limits<double>::infinity();
  if (distance > o.max_distance || !(sigma_z / std::max(best.Z, 1e-6) <= o.max_relative_uncertainty)) uncertain = true;
  if (uncertain) box.flags |= BESLAM_BOX_UNCERTAIN;

  // The centre's noise in the bird's-eye view. Along the line of sight, each frame: the road contact's
  // distance error, sigma_z above (the bottom edge's pixels and the camera's pitch against the road, which
  // the car's own pitching changes from frame to frame, through dv/dZ, which falls with the square of the
  // distance), or for a box placed by its class height the box's pixel height. Across it: the box centre's
  // pixel noise at that distance.
  const double range_bev = std::hypot(center.x(), center.z());
  const double sigma_height_prior = best.Z * std::sqrt(2.0) * o.pixel_sigma / std::max(y2 - y1, 1.0);
  const double sigma_depth = std::isfinite(sigma_z) ? sigma_z : sigma_height_prior;
  box.position_sigma[0] = sigma_depth * range_bev / std::max(best.Z, 1e-6);
  // The road's own slope is not new each frame: its range error, Z^2 pitch / H, changes by 2 Z pitch / H per
  // metre of range. A box placed by its class height is off by its car's height against the prior, the
  // same fraction at every range.
  box.range_drift = std::isfinite(sigma_z) ? 2 * best.Z * o.pitch_sigma / o.camera_height : kClassHeightSpread;
  box.position_sigma[1] = range_bev * o.pixel_sigma / g.fx;
  // A box cut by the image border shows part of its object: the centre is known to about half its length.
  if (cut_left || cut_right || cut_bottom)
    for (double& s : box.position_sigma) s = std::max(s, 0.5 * size[0]);
  box.flags |= BESLAM_BOX_HAS_POSITION_SIGMA;
  return box;
}

}  // namespace beslam::detector_image
