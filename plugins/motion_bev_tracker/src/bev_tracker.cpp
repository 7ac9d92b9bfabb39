#include "beslam/motion/bev_tracker.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "beslam/motion/hungarian.hpp"

namespace beslam::motion {

namespace {

// Kalman update of the state (x z vx vz) by a measurement z of its first K components with covariance R.
template <int K>
void kalmanUpdate(Eigen::Vector4d& x, Eigen::Matrix4d& P, const Eigen::Matrix<double, K, 1>& z,
                  const Eigen::Matrix<double, K, K>& R) {
  const Eigen::Matrix<double, K, 4> H = Eigen::Matrix<double, K, 4>::Identity();
  const Eigen::Matrix<double, K, K> S = H * P * H.transpose() + R;
  const Eigen::Matrix<double, 4, K> gain = P * H.transpose() * S.inverse();
  x += gain * (z - H * x);
  P = (Eigen::Matrix4d::Identity() - gain * H) * P;
}

constexpr double kNoMatch = 1e6;    // cost of a gated-out pair
constexpr double kRoadSpeed = 1.0;  // m/s: an ego slower than this gives no road direction
constexpr double kGateChi2 = 13.8;  // a box with its own noise: innovation chi-square gate (2 dof, 99.9 %)
// A box cut by the image border and its track's box of the frame before: at 10 Hz a car leaving the view moves
// a fraction of its width between frames, and the cut keeps the part still in view, so the two overlap by far
// more than two neighbouring cars' boxes do.
constexpr double kCutBoxMinIou = 0.3;

// Throws std::invalid_argument on a box with a non-finite field or a negative sigma.
void checkBoxes(const std::vector<beslam_box3d>& boxes) {
  for (size_t i = 0; i < boxes.size(); ++i) {
    const beslam_box3d& b = boxes[i];
    bool ok = std::isfinite(b.yaw) && std::isfinite(b.size[0]) && std::isfinite(b.size[1]);
    for (double v : b.center_cam) ok = ok && std::isfinite(v);
    if ((b.flags & BESLAM_BOX_HAS_VELOCITY) != 0)
      for (double v : b.velocity_cam) ok = ok && std::isfinite(v);
    if ((b.flags & BESLAM_BOX_HAS_POSITION_SIGMA) != 0)
      ok = ok && std::isfinite(b.position_sigma[0]) && std::isfinite(b.position_sigma[1]) &&
           std::isfinite(b.range_drift) && b.position_sigma[0] >= 0 && b.position_sigma[1] >= 0 && b.range_drift >= 0;
    if (!ok)
      throw std::invalid_argument("motion tracker: box " + std::to_string(i) +
                                  " has a non-finite field or a negative sigma");
  }
}

// IoU of two image rectangles (x1 y1 x2 y2).
double boxIoU2d(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
  const double w = std::min(a[2], b[2]) - std::max(a[0], b[0]), h = std::min(a[3], b[3]) - std::max(a[1], b[1]);
  if (w <= 0 || h <= 0) return 0;
  const double inter = w * h, area_a = (a[2] - a[0]) * (a[3] - a[1]), area_b = (b[2] - b[0]) * (b[3] - b[1]);
  return inter / (area_a + area_b - inter);
}

bool carLike(int32_t c) { return c == BESLAM_CLASS_CAR || c == BESLAM_CLASS_VAN || c == BESLAM_CLASS_TRUCK; }

bool compatible(int32_t a, int32_t b, bool any) {
  if (any || a == b || a == BESLAM_CLASS_UNKNOWN || b == BESLAM_CLASS_UNKNOWN) return true;
  return carLike(a) && carLike(b);
}

using Poly = std::vector<Eigen::Vector2d>;

Poly rectangle(const Eigen::Vector2d& c, double yaw, double l, double w) {
  const Eigen::Vector2d ax(std::cos(yaw), std::sin(yaw)), ay(-std::sin(yaw), std::cos(yaw));
  const Eigen::Vector2d a = ax * (l / 2), b = ay * (w / 2);
  return {c + a + b, c - a + b, c - a - b, c + a - b};  // counter-clockwise
}

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

double area(const Poly& p) {
  double s = 0;
  for (size_t i = 0; i < p.size(); ++i) s += cross(p[i], p[(i + 1) % p.size()]);
  return std::abs(s) / 2;
}

// Clips convex polygon `subject` by convex counter-clockwise polygon `clip` (Sutherland-Hodgman).
Poly clipConvex(Poly subject, const Poly& clip) {
  for (size_t e = 0; e < clip.size() && !subject.empty(); ++e) {
    const Eigen::Vector2d a = clip[e], b = clip[(e + 1) % clip.size()];
    auto inside = [&](const Eigen::Vector2d& p) { return cross(b - a, p - a) >= 0; };
    Poly out;
    for (size_t i = 0; i < subject.size(); ++i) {
      const Eigen::Vector2d p = subject[i], q = subject[(i + 1) % subject.size()];
      const bool pin = inside(p), qin = inside(q);
      if (pin) out.push_back(p);
      if (pin != qin) {
        const double dp = cross(b - a, p - a), dq = cross(b - a, q - a);
        out.push_back(p + (q - p) * (dp / (dp - dq)));
      }
    }
    subject = std::move(out);
  }
  return subject;
}

Eigen::Isometry3d scaleMotion(const Eigen::Isometry3d& delta, double s) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  const Eigen::AngleAxisd aa(delta.linear());
  out.linear() = Eigen::AngleAxisd(aa.angle() * s, aa.axis()).toRotationMatrix();
  out.translation() = delta.translation() * s;
  return out;
}

}  // namespace

double bevYaw(const Eigen::Matrix3d& R_world_cam, double yaw_cam) {
  const Eigen::Vector3d heading_cam(std::cos(yaw_cam), 0.0, -std::sin(yaw_cam));  // box x axis (KITTI ry)
  const Eigen::Vector3d h = R_world_cam * heading_cam;
  return std::atan2(h.z(), h.x());
}

double rotatedRectIoU(const Eigen::Vector2d& c1, double yaw1, double l1, double w1, const Eigen::Vector2d& c2,
                      double yaw2, double l2, double w2) {
  const double r1 = std::hypot(l1, w1) / 2, r2 = std::hypot(l2, w2) / 2;
  if ((c1 - c2).norm() > r1 + r2) return 0.0;
  const Poly a = rectangle(c1, yaw1, l1, w1), b = rectangle(c2, yaw2, l2, w2);
  const double inter = area(clipConvex(a, b));
  const double uni = l1 * w1 + l2 * w2 - inter;
  return uni > 0 ? inter / uni : 0.0;
}

std::string Params::validate() const {
  if (association != "distance" && association != "iou") return "association must be distance or iou";
  if (!(parallax_tolerance > 0 && parallax_tolerance < 1)) return "parallax_tolerance must be in (0, 1)";
  if (parallax) {
    const std::string problem = parallax_check.validate();
    if (!problem.empty()) return problem;
  }
  if (!(gate > 0)) return "gate must be > 0";
  if (!(gate_per_m >= 0)) return "gate_per_m must be >= 0";
  if (!(min_iou > 0 && min_iou < 1)) return "min_iou must be in (0, 1)";
  if (!(accel_sigma > 0)) return "accel_sigma must be > 0";
  if (!(pos_sigma > 0)) return "pos_sigma must be > 0";
  if (!(pos_sigma_per_m >= 0)) return "pos_sigma_per_m must be >= 0";
  if (!(velocity_sigma > 0)) return "velocity_sigma must be > 0";
  if (!(ego_speed_noise >= 0) || !(ego_turn_noise >= 0)) return "ego_speed_noise and ego_turn_noise must be >= 0";
  if (!(settling_speed_noise >= 0) || !(settling_time >= 0))
    return "settling_speed_noise and settling_time must be >= 0";
  if (reference_tracks < 0) return "reference_tracks must be >= 0";
  if (!(init_velocity_sigma > 0)) return "init_velocity_sigma must be > 0";
  if (!(max_miss_time >= 0)) return "max_miss_time must be >= 0";
  if (max_history < 2) return "max_history must be >= 2";
  if (!(window_dynamic > 0) || !(window_static > 0)) return "window_dynamic and window_static must be > 0";
  if (min_observations < 2) return "min_observations must be >= 2";
  if (!(max_residual > 0)) return "max_residual must be > 0";
  if (!(displacement_margin >= 0)) return "displacement_margin must be >= 0";
  if (anchor_frames < 1) return "anchor_frames must be >= 1";
  if (!(dynamic_speed >= 0) || !(static_speed > 0)) return "dynamic_speed must be >= 0 and static_speed > 0";
  if (!(z_dynamic >= 0) || !(z_static >= 0)) return "z_dynamic and z_static must be >= 0";
  if (start_frames < 1 || pull_out_frames < 1 || stop_dwell < 1)
    return "start_frames, pull_out_frames and stop_dwell must be >= 1";
  if (!(max_range > 0)) return "max_range must be > 0";
  if (!(default_dt > 0)) return "default_dt must be > 0";
  return {};
}

BevTracker::BevTracker(const Params& params) : params_(params) {
  const std::string problem = params.validate();
  if (!problem.empty()) throw std::invalid_argument("motion tracker: " + problem);
}

void BevTracker::reset() {
  tracks_.clear();
  next_id_ = 0;
  have_time_ = false;
  pose_mode_ = false;
  poses_.clear();
  jitter_.clear();
  scale_change_t_ = scale_change_ = 0;
  jitter_rms_ = 0;
  ego_speed_ = ego_yaw_rate_ = 0;
  ego_velocity_ = Eigen::Vector2d::Zero();
  last_frame_posed_ = false;
}

void BevTracker::worldMoved(const Eigen::Isometry3d& S_new_old, double scale) {
  if (!S_new_old.matrix().allFinite() || !std::isfinite(scale) || !(scale > 0))
    throw std::invalid_argument("motion tracker: a world change needs a finite transform and a scale > 0");
  if (!pose_mode_) return;  // nothing placed in the world yet
  if (std::abs(scale - 1.0) > 1e-9) scale_change_t_ = last_time_, scale_change_ = std::abs(scale - 1.0);
  // A camera centre moves with the change, scale included; a box's offset from the camera that saw it is in
  // metres (the detector's), so it only turns with the camera. In the BEV plane: a point is lifted to the
  // height of the latest camera (a correction's tilt is a fraction of a degree), moved, and projected again.
  const Eigen::Matrix3d R = S_new_old.linear();
  auto move = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(scale * (R * p) + S_new_old.translation()); };
  const double y = poses_.empty() ? 0.0 : poses_.back().second.translation().y();
  auto moveCentre = [&](const Eigen::Vector2d& c) {
    const Eigen::Vector3d q = move(Eigen::Vector3d(c.x(), y, c.y()));
    return Eigen::Vector2d(q.x(), q.z());
  };
  Eigen::Matrix2d L;  // the turn of BEV vectors (offsets, velocities, covariances)
  L << R(0, 0), R(0, 2), R(2, 0), R(2, 2);
  auto seenFrom = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& cam) {
    return Eigen::Vector2d(moveCentre(cam) + L * (p - cam));
  };
  Eigen::Matrix4d J = Eigen::Matrix4d::Zero();
  J.topLeftCorner<2, 2>() = J.bottomRightCorner<2, 2>() = L;
  auto turn = [&](double yaw) {
    const Eigen::Vector2d h = L * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
    return std::atan2(h.y(), h.x());
  };
  for (Track& t : tracks_) {
    const Eigen::Vector2d last_cam = t.history.empty() ? Eigen::Vector2d(t.x.head<2>()) : t.history.back().cam;
    t.x.head<2>() = seenFrom(t.x.head<2>(), last_cam);
    t.x.tail<2>() = L * t.x.tail<2>();
    t.P = J * t.P * J.transpose();
    t.yaw_bev = turn(t.yaw_bev);
    for (Observation& o : t.history) {
      o.p = seenFrom(o.p, o.cam);
      o.cam = moveCentre(o.cam);
      o.cov = L * o.cov * L.transpose();
      o.drift_cov = L * o.drift_cov * L.transpose();
    }
    t.anchor = seenFrom(t.anchor, t.anchor_cam);
    t.anchor_cam = moveCentre(t.anchor_cam);
    t.anchor_cov = L * t.anchor_cov * L.transpose();
  }
  for (auto& [t, T_world_cam] : poses_) {
    T_world_cam.translation() = move(T_world_cam.translation());
    T_world_cam.linear() = R * T_world_cam.linear();
  }
  ego_velocity_ = scale * (L * ego_velocity_);
  ego_speed_ *= scale;
}

BevTracker::Speed BevTracker::fitSpeed(const Track& track, double window,
                                       const std::optional<Eigen::Vector2d>& det_velocity, double det_sigma,
                                       bool dynamic_test) const {
  Speed s;
  const auto& h = track.history;
  Eigen::Vector2d v_fit = Eigen::Vector2d::Zero();
  double sigma_fit = 0, sigma_bound = 0;
  double speed_bound = -1;  // set by the anisotropic fit; else speed + z_static * sigma_bound
  bool fit = false;
  if (!h.empty()) {
    const double t_end = h.back().t;
    size_t first = h.size();
    while (first > 0 && h[first - 1].t >= t_end - window - 1e-6) --first;
    const size_t n = h.size() - first;
    const bool enough = static_cast<int>(n) >= params_.min_observations;
    const bool isotropic = std::all_of(h.begin() + static_cast<std::ptrdiff_t>(first), h.end(),
                                       [](const Observation& o) { return o.isotropic; });
    if (enough && !isotropic) {
      const std::optional<Fit> g = fitSpeedAnisotropic(h, first, dynamic_test);
      if (g) {
        v_fit = g->velocity, sigma_fit = g->sigma, sigma_bound = g->sigma_bound, fit = g->consistent;
        speed_bound = g->speed_bound;
      }
    } else if (enough) {
      double t_mean = 0, var_model = 0, var_ego = 0;
      Eigen::Vector2d p_mean = Eigen::Vector2d::Zero();
      for (size_t i = first; i < h.size(); ++i) {
        t_mean += h[i].t, p_mean += h[i].p, var_model += h[i].cov(0, 0);  // sigma^2: isotropic
        var_ego += h[i].v_sigma * h[i].v_sigma + (dynamic_test ? h[i].v_settling * h[i].v_settling : 0.0);
      }
      t_mean /= static_cast<double>(n), p_mean /= static_cast<double>(n), var_model /= static_cast<double>(n);
      var_ego /= static_cast<double>(n);
      double stt = 0;
      Eigen::Vector2d stp = Eigen::Vector2d::Zero();
      for (size_t i = first; i < h.size(); ++i) {
        const double dt = h[i].t - t_mean;
        stt += dt * dt;
        stp += dt * (h[i].p - p_mean);
      }
      if (stt > 1e-9) {
        v_fit = stp / stt;
        double var = var_model;
        bool consistent = true;
        if (n > 2) {
          double rss = 0;
          for (size_t i = first; i < h.size(); ++i) rss += (h[i].p - p_mean - v_fit * (h[i].t - t_mean)).squaredNorm();
          const double var_residual = rss / (2.0 * static_cast<double>(n - 2));
          // Positions that no straight line explains (a track that jumped between objects) give no evidence.
          consistent = var_residual <= params_.max_residual * params_.max_residual * var_model;
          var = std::max(var, var_residual);
        }
        // Detection noise averages down with the window's length and number of positions (sum of (t - t_mean)^2);
        // the ego-motion error is a velocity bias shared by all of them and does not.
        sigma_fit = std::sqrt(var / stt + var_ego);
        sigma_bound = sigma_fit;
        fit = consistent;
      }
    }
  }
  if (det_velocity) {
    if (fit) {
      const double w1 = 1 / (sigma_fit * sigma_fit), w2 = 1 / (det_sigma * det_sigma);
      v_fit = (w1 * v_fit + w2 * *det_velocity) / (w1 + w2);
      sigma_fit = 1 / std::sqrt(w1 + w2);
      sigma_bound = 1 / std::sqrt(1 / (sigma_bound * sigma_bound) + w2);
    } else {
      v_fit = *det_velocity;
      sigma_fit = sigma_bound = det_sigma;
    }
    fit = true;
  }
  if (!fit) return s;
  s.valid = true;
  s.velocity = v_fit;
  s.speed = v_fit.norm();
  s.sigma = sigma_fit;
  s.sigma_bound = sigma_bound;
  s.speed_bound = det_velocity || speed_bound < 0 ? s.speed + params_.z_static * sigma_bound : speed_bound;
  return s;
}

std::optional<BevTracker::Fit> BevTracker::fitSpeedAnisotropic(const std::deque<Observation>& h, size_t first,
                                                               bool dynamic_test) const {
  // Generalised least squares of p_i = a + v (t_i - t_mean), each position weighted by its inverse
  // covariance: a range error along the line of sight says nothing about the motion across it.
  const size_t n = h.size() - first;
  double t_mean = 0, var_ego = 0, stt = 0;
  Eigen::Vector2d p_mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d drift = Eigen::Matrix2d::Zero();
  for (size_t i = first; i < h.size(); ++i) {
    t_mean += h[i].t, p_mean += h[i].p, var_ego += h[i].v_sigma * h[i].v_sigma;
    if (dynamic_test) var_ego += h[i].v_settling * h[i].v_settling;
    drift += h[i].drift_cov;
  }
  t_mean /= static_cast<double>(n), p_mean /= static_cast<double>(n), var_ego /= static_cast<double>(n);
  drift /= static_cast<double>(n);
  for (size_t i = first; i < h.size(); ++i) stt += (h[i].t - t_mean) * (h[i].t - t_mean);
  if (!(stt > 1e-9)) return std::nullopt;
  Eigen::Matrix4d N = Eigen::Matrix4d::Zero();
  Eigen::Vector4d g = Eigen::Vector4d::Zero();
  std::vector<Eigen::Matrix2d> W(n);
  for (size_t i = first; i < h.size(); ++i) {
    const double dt = h[i].t - t_mean;
    const Eigen::Matrix2d& w = W[i - first] = h[i].cov.inverse();
    const Eigen::Vector2d q = h[i].p - p_mean;
    N.topLeftCorner<2, 2>() += w;
    N.topRightCorner<2, 2>() += dt * w;
    N.bottomRightCorner<2, 2>() += dt * dt * w;
    g.head<2>() += w * q;
    g.tail<2>() += dt * (w * q);
  }
  N.bottomLeftCorner<2, 2>() = N.topRightCorner<2, 2>().transpose();
  const Eigen::LDLT<Eigen::Matrix4d> ldlt(N);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  const Eigen::Vector4d x = ldlt.solve(g);
  Fit f;
  f.velocity = x.tail<2>();
  double scale = 1;  // the residual spread, when it is larger than the model
  if (n > 2) {
    double chi2 = 0;
    for (size_t i = first; i < h.size(); ++i) {
      const Eigen::Vector2d r = h[i].p - p_mean - x.head<2>() - f.velocity * (h[i].t - t_mean);
      chi2 += r.dot(W[i - first] * r);
    }
    const double per_dof = chi2 / (2.0 * static_cast<double>(n - 2));
    f.consistent = per_dof <= params_.max_residual * params_.max_residual;
    scale = std::max(1.0, per_dof);
  }
  // The velocity's covariance: detection noise (what more positions average away) and the errors they
  // share, the ego-motion error (isotropic) and the boxes' range drift (along their lines of sight).
  const Eigen::Matrix2d C = scale * ldlt.solve(Eigen::Matrix4d::Identity()).bottomRightCorner<2, 2>() + drift +
                            var_ego * Eigen::Matrix2d::Identity();
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(C, Eigen::EigenvaluesOnly).eigenvalues()(1);
  const double speed = f.velocity.norm();
  const double along = speed > 1e-9 ? f.velocity.dot(C * f.velocity) / (speed * speed) : largest;
  f.sigma = std::sqrt(along);
  f.sigma_bound = std::sqrt(largest);
  f.speed_bound = speed + params_.z_static * f.sigma_bound;
  if (ego_speed_ > kRoadSpeed) {
    // Traffic moves along the road, which runs along the ego's own travel: a speed along the road is
    // seen across the line of sight of every car not straight ahead, where the boxes are precise. So a
    // car is also shown slower than a speed when both its speed along the road (the velocity constrained
    // to that direction) and its velocity across the road (unconstrained) are.
    const Eigen::Vector2d d = ego_velocity_.normalized(), e(-d.y(), d.x());
    const Eigen::Matrix2d C_inv = C.inverse();
    const double info = d.dot(C_inv * d);
    const double s_road = d.dot(C_inv * f.velocity) / info;
    const double bound_road = std::abs(s_road) + params_.z_static * std::sqrt(1 / info);
    const double bound_across = std::abs(e.dot(f.velocity)) + params_.z_static * std::sqrt(e.dot(C * e));
    f.speed_bound = std::min(f.speed_bound, std::max(bound_road, bound_across));
  }
  return f;
}

void BevTracker::decide(Track& track, const std::optional<Eigen::Vector2d>& det_velocity, Decision& out) {
  const Speed dyn = fitSpeed(track, params_.window_dynamic, det_velocity, params_.velocity_sigma, true);
  const Speed sta = fitSpeed(track, params_.window_static, det_velocity, params_.velocity_sigma, false);
  // The parked cars around: their common apparent velocity is the pose source's error, not motion.
  const std::optional<std::pair<Eigen::Vector2d, double>> reference =
      det_velocity ? std::nullopt : parkedReference(track.id);
  // A static track also moves when its latest positions leave the place it was parked at.
  bool displaced = false;
  if (track.state == BESLAM_MOTION_STATIC && track.anchor_n > 0 && !track.history.empty()) {
    const size_t k = std::min<size_t>(3, track.history.size());
    Eigen::Vector2d recent = Eigen::Vector2d::Zero();
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero(), range_drift = Eigen::Matrix2d::Zero();
    double v_sigma = 0, t_recent = 0;
    for (size_t i = track.history.size() - k; i < track.history.size(); ++i) {
      const Observation& o = track.history[i];
      recent += o.p, cov += o.cov, v_sigma += std::hypot(o.v_sigma, o.v_settling), t_recent += o.t,
          range_drift += o.drift_cov;
    }
    recent /= static_cast<double>(k);
    const double since = std::max(0.0, t_recent / static_cast<double>(k) - track.anchor_t);
    // The boxes' range drift since the parked position was measured, along their lines of sight.
    cov = cov / static_cast<double>(k * k) + track.anchor_cov + range_drift / static_cast<double>(k) * since * since;
    // The noise along the displacement (a range error moves a box along its line of sight only).
    Eigen::Vector2d step = recent - track.anchor;
    if (reference) {  // the parked cars around have drifted with it since (at their velocity now)
      step -= reference->first * since;
      cov += std::pow(reference->second * since, 2) * Eigen::Matrix2d::Identity();
    }
    double var = step.norm() > 1e-12 ? step.dot(cov * step) / step.squaredNorm() : 0.5 * cov.trace();
    // Pose drift since the parked position was measured: the ego-motion velocity error over that time.
    const double drift = v_sigma / static_cast<double>(k) * since;
    var += drift * drift;
    displaced = step.norm() > params_.z_dynamic * std::sqrt(var) + params_.displacement_margin;
  }
  double dyn_speed = dyn.speed, dyn_sigma = dyn.sigma;
  if (dyn.valid && reference) {  // the speed against the parked cars around
    dyn_speed = (dyn.velocity - reference->first).norm();
    dyn_sigma = std::hypot(dyn.sigma, reference->second);
  }
  // A recent parallax measurement within the tolerance outranks the lifted boxes' speed (parallaxEvidence).
  const bool parallax_holds = params_.parallax && last_time_ - track.parallax_t <= params_.window_static;
  const bool dynamic_evidence =
      !parallax_holds &&
      (displaced || (dyn.valid && dyn_speed - params_.z_dynamic * dyn_sigma > params_.dynamic_speed));
  const bool static_evidence = !dynamic_evidence && sta.valid && sta.speed_bound < params_.static_speed;
  if (dynamic_evidence) {
    ++track.dynamic_run;
    track.static_run = 0;
  } else if (static_evidence) {
    ++track.static_run;
    track.dynamic_run = 0;
  }  // no evidence either way: both runs continue (only contrary evidence breaks a run)
  switch (track.state) {
    case BESLAM_MOTION_UNKNOWN:
      if (track.dynamic_run >= params_.start_frames)
        track.state = BESLAM_MOTION_DYNAMIC;
      else if (static_evidence)
        track.state = BESLAM_MOTION_STATIC;
      break;
    case BESLAM_MOTION_STATIC:
      if (track.dynamic_run >= params_.pull_out_frames) track.state = BESLAM_MOTION_DYNAMIC;
      break;
    case BESLAM_MOTION_DYNAMIC:
      if (track.static_run >= params_.stop_dwell) track.state = BESLAM_MOTION_STATIC;
      break;
  }
  // The parked position: a running mean (at most anchor_frames deep, so slow pose drift is forgiven).
  if (track.state == BESLAM_MOTION_STATIC && !displaced && !track.history.empty()) {
    const Observation& o = track.history.back();
    track.anchor_n = std::min(track.anchor_n + 1, params_.anchor_frames);
    track.anchor = track.anchor_n == 1 ? o.p : Eigen::Vector2d(track.anchor + (o.p - track.anchor) / track.anchor_n);
    track.anchor_t = track.anchor_n == 1 ? o.t : track.anchor_t + (o.t - track.anchor_t) / track.anchor_n;
    track.anchor_cam =
        track.anchor_n == 1 ? o.cam : Eigen::Vector2d(track.anchor_cam + (o.cam - track.anchor_cam) / track.anchor_n);
    track.anchor_cov = o.cov / track.anchor_n;
  } else if (track.state != BESLAM_MOTION_STATIC) {
    track.anchor_n = 0;
  }
  out.speed = dyn.valid ? dyn.speed : 0;
  out.speed_sigma = dyn.valid ? dyn.sigma : 0;
}

std::optional<std::pair<Eigen::Vector2d, double>> BevTracker::parkedReference(int32_t track_id) const {
  std::vector<double> vx, vz, sigma;
  for (const Reference& r : references_)
    if (r.track_id != track_id) vx.push_back(r.velocity.x()), vz.push_back(r.velocity.y()), sigma.push_back(r.sigma);
  if (params_.reference_tracks <= 0 || static_cast<int>(vx.size()) < params_.reference_tracks) return std::nullopt;
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  // The median of n velocities has about 1.25 times the standard error of their mean.
  const double n = static_cast<double>(vx.size());
  return std::make_pair(Eigen::Vector2d(median(vx), median(vz)), 1.2533 * median(sigma) / std::sqrt(n));
}

Eigen::Isometry3d BevTracker::steadyPose(double now) const {
  const auto& [t1, T1] = poses_.back();
  if (poses_.size() < 2 || !(t1 > poses_[0].first)) return T1;
  return T1 * scaleMotion(poses_[0].second.inverse() * T1, (now - t1) / (t1 - poses_[0].first));
}

double BevTracker::advanceTime(double timestamp, double& dt) {
  if (have_time_ && std::isfinite(timestamp) && timestamp > last_time_) dt = timestamp - last_time_;
  const double now = have_time_ ? last_time_ + dt : (std::isfinite(timestamp) ? timestamp : 0.0);
  have_time_ = true;
  last_time_ = now;
  return now;
}

bool BevTracker::takePose(double now, const std::optional<Eigen::Isometry3d>& T_world_cam_in,
                          std::optional<Eigen::Isometry3d>& T_world_cam, bool& extrapolated) {
  T_world_cam = T_world_cam_in;
  extrapolated = false;
  if (T_world_cam) {
    if (!T_world_cam->matrix().allFinite()) throw std::invalid_argument("motion tracker: non-finite camera pose");
    if (!pose_mode_) {  // tracks built in the camera frame cannot continue in the world frame
      tracks_.clear();
      pose_mode_ = true;
      first_pose_t_ = now;
    }
    // Jitter is measured between consecutive given poses only: after a gap the prediction spans the gap,
    // and how far the ego's real path leaves a straight extrapolation over seconds is no pose error.
    if (params_.pose_jitter && last_frame_posed_ && poses_.size() == 2 && poses_[1].first > poses_[0].first &&
        now > poses_[1].first) {
      // How far the pose is from where steady motion would have put it: a real vehicle's acceleration
      // explains centimetres at 10 Hz, a backend's map correction decimetres to metres.
      const Eigen::Vector3d d = T_world_cam->translation() - steadyPose(now).translation();
      jitter_.emplace_back(now, d.x() * d.x() + d.z() * d.z());
    }
    while (!jitter_.empty() && jitter_.front().first < now - params_.window_static - 1e-6) jitter_.pop_front();
    double sum = 0;
    for (const auto& j : jitter_) sum += j.second;
    jitter_rms_ = jitter_.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(jitter_.size()));
    poses_.emplace_back(now, *T_world_cam);
    if (poses_.size() > 2) poses_.erase(poses_.begin());
    if (poses_.size() == 2 && poses_[1].first > poses_[0].first) {
      // The ego's own motion between the last two poses: BEV speed and yaw rate (the rotation's angle).
      const double span = poses_[1].first - poses_[0].first;
      const Eigen::Vector3d d = poses_[1].second.translation() - poses_[0].second.translation();
      ego_speed_ = std::hypot(d.x(), d.z()) / span;
      ego_yaw_rate_ =
          Eigen::AngleAxisd(poses_[0].second.linear().transpose() * poses_[1].second.linear()).angle() / span;
      ego_velocity_ = Eigen::Vector2d(d.x(), d.z()) / span;
    }
  } else if (!poses_.empty() && now - poses_.back().first > params_.max_miss_time) {
    last_frame_posed_ = false;
    return false;
  } else if (!poses_.empty()) {
    T_world_cam = steadyPose(now);
    extrapolated = true;
  }
  return true;
}

void BevTracker::predict(double dt) {
  const double q = params_.accel_sigma * params_.accel_sigma;
  Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
  F(0, 2) = F(1, 3) = dt;
  Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();
  Q(0, 0) = Q(1, 1) = q * dt * dt * dt * dt / 4;
  Q(0, 2) = Q(2, 0) = Q(1, 3) = Q(3, 1) = q * dt * dt * dt / 2;
  Q(2, 2) = Q(3, 3) = q * dt * dt;
  for (Track& t : tracks_) {
    t.x = F * t.x;
    t.P = F * t.P * F.transpose() + Q;
  }
}

BevTracker::Placed BevTracker::place(const std::vector<beslam_box3d>& boxes, const Eigen::Isometry3d& T_wc,
                                     double now) const {
  const size_t n = boxes.size();
  const Eigen::Matrix3d R_wc = T_wc.linear();
  Placed out;
  std::vector<Eigen::Vector2d>& p = out.p;
  std::vector<double>& range = out.range;
  std::vector<double>& v_sigma = out.v_sigma;
  std::vector<double>& yaw = out.yaw;
  p.resize(n), range.resize(n), v_sigma.resize(n), yaw.resize(n);
  const double settling_share =
      std::max(now - first_pose_t_ < params_.settling_time ? params_.settling_speed_noise : 0.0,
               now - scale_change_t_ < params_.settling_time ? scale_change_ : 0.0);
  out.v_settling = settling_share * ego_speed_;
  std::vector<Eigen::Matrix2d>& cov = out.cov;
  std::vector<Eigen::Matrix2d>& drift_cov = out.drift_cov;
  std::vector<Eigen::Vector2d>& line_of_sight = out.line_of_sight;
  std::vector<std::optional<Eigen::Vector2d>>& vel = out.vel;
  cov.resize(n), drift_cov.assign(n, Eigen::Matrix2d::Zero()), line_of_sight.assign(n, Eigen::Vector2d::Zero()),
      vel.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const beslam_box3d& b = boxes[i];
    const Eigen::Vector3d c_cam(b.center_cam[0], b.center_cam[1], b.center_cam[2]);
    const Eigen::Vector3d c_w = T_wc * c_cam;
    p[i] = Eigen::Vector2d(c_w.x(), c_w.z());
    range[i] = std::hypot(c_cam.x(), c_cam.z());
    const double model = params_.pos_sigma + params_.pos_sigma_per_m * range[i];
    const Eigen::Vector2d sight(c_w.x() - T_wc.translation().x(), c_w.z() - T_wc.translation().z());
    if ((b.flags & BESLAM_BOX_HAS_POSITION_SIGMA) != 0 && sight.norm() > 1e-6) {
      // The detector's own range and bearing noise (the model is the floor), with the pose jitter.
      const double s_range = std::hypot(std::max(b.position_sigma[0], model), jitter_rms_);
      const double s_across = std::hypot(std::max(b.position_sigma[1], model), jitter_rms_);
      line_of_sight[i] = sight.normalized();
      cov[i] = s_across * s_across * Eigen::Matrix2d::Identity() +
               (s_range * s_range - s_across * s_across) * line_of_sight[i] * line_of_sight[i].transpose();
      // Range drift: a parked car closes in at the ego's speed along the line of sight.
      const double s = b.range_drift * std::abs(line_of_sight[i].dot(ego_velocity_));
      drift_cov[i] = s * s * line_of_sight[i] * line_of_sight[i].transpose();
    } else {
      const double sigma = std::hypot(model, jitter_rms_);
      cov[i] = sigma * sigma * Eigen::Matrix2d::Identity();
    }
    v_sigma[i] = params_.ego_speed_noise * ego_speed_ + params_.ego_turn_noise * ego_yaw_rate_ * range[i];
    yaw[i] = bevYaw(R_wc, b.yaw);
    if (b.flags & BESLAM_BOX_HAS_VELOCITY) {
      const Eigen::Vector3d v_w = R_wc * Eigen::Vector3d(b.velocity_cam[0], b.velocity_cam[1], b.velocity_cam[2]);
      vel[i] = Eigen::Vector2d(v_w.x(), v_w.z());
    }
  }
  return out;
}

std::vector<int> BevTracker::associate(const std::vector<beslam_box3d>& boxes, const Placed& placed) const {
  const size_t n = boxes.size(), m = tracks_.size();
  const std::vector<Eigen::Vector2d>& p = placed.p;
  const std::vector<double>& range = placed.range;
  const std::vector<double>& yaw = placed.yaw;
  const std::vector<Eigen::Matrix2d>& cov = placed.cov;
  const std::vector<Eigen::Vector2d>& line_of_sight = placed.line_of_sight;
  std::vector<int> det_to_track(n, -1);
  if (n > 0 && m > 0) {
    std::vector<double> cost(n * m, kNoMatch);
    const bool iou = params_.association == "iou";
    for (size_t i = 0; i < n; ++i) {
      for (size_t j = 0; j < m; ++j) {
        const Track& t = tracks_[j];
        if (!compatible(boxes[i].class_id, t.class_id, params_.match_across_classes)) continue;
        const Eigen::Vector2d pred = t.x.head<2>();
        if (iou) {
          const double o =
              rotatedRectIoU(p[i], yaw[i], boxes[i].size[0], boxes[i].size[1], pred, t.yaw_bev, t.length, t.width);
          if (o >= params_.min_iou) cost[i * m + j] = 1.0 - o;
        } else {
          const Eigen::Vector2d e = p[i] - pred;
          const double gate = params_.gate + params_.gate_per_m * range[i];
          double d = e.norm();
          if (line_of_sight[i].squaredNorm() > 0) {
            // A range error is no evidence of another object: the distance along the line of sight counts
            // in units of the noise across it, and is gated by the innovation's own covariance.
            const Eigen::Vector2d u = line_of_sight[i], v(-u.y(), u.x());
            const double excess = std::sqrt(std::max(0.0, u.dot(cov[i] * u) - v.dot(cov[i] * v)));
            const Eigen::Matrix2d S = t.P.topLeftCorner<2, 2>() + cov[i];
            if (e.dot(S.inverse() * e) > kGateChi2) continue;
            d = std::hypot(v.dot(e), u.dot(e) * gate / (gate + 3 * excess));
          }
          const double spread = std::min(2.0 * std::sqrt(t.P(0, 0) + t.P(1, 1)), params_.gate);
          if (d <= gate + spread) cost[i * m + j] = d;
        }
      }
    }
    const std::vector<int> a = solveAssignment(cost, static_cast<int>(n), static_cast<int>(m));
    for (size_t i = 0; i < n; ++i)
      if (a[i] >= 0 && cost[i * m + static_cast<size_t>(a[i])] < kNoMatch) det_to_track[i] = a[i];
  }
  return det_to_track;
}

int BevTracker::matchByImageBox(const beslam_box3d& b, const std::vector<char>& matched, double now, double dt) const {
  // A box cut by the image border is lifted to where its visible part would stand, which jumps away from its
  // track in the BEV; in the image it still overlaps the track's box of the frame before.
  if ((b.flags & BESLAM_BOX_HAS_BBOX2D) == 0) return -1;
  const Eigen::Vector4d box2d(b.bbox2d[0], b.bbox2d[1], b.bbox2d[2], b.bbox2d[3]);
  double best = kCutBoxMinIou;
  int found = -1;
  for (size_t j = 0; j < matched.size(); ++j) {
    const Track& c = tracks_[j];
    if (matched[j] || c.bbox2d_t < 0 || now - c.bbox2d_t > 1.5 * dt) continue;
    if (!compatible(b.class_id, c.class_id, params_.match_across_classes)) continue;
    const double o = boxIoU2d(box2d, c.bbox2d);
    if (o > best) best = o, found = static_cast<int>(j);
  }
  return found;
}

void BevTracker::dropMissed(size_t old_count, const std::vector<char>& matched, double now, double dt) {
  // Tracks missed too long go (tentative ones sooner).
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (size_t j = 0; j < tracks_.size(); ++j) {
    Track& t = tracks_[j];
    const bool is_old = j < old_count;
    if (is_old && !matched[j]) {
      const double missing = now - t.last_t;
      const double limit =
          t.hits < params_.min_observations ? std::min(params_.max_miss_time, 2.5 * dt) : params_.max_miss_time;
      if (missing > limit + 1e-9) continue;
    }
    kept.push_back(std::move(t));
  }
  tracks_ = std::move(kept);
}

std::vector<Decision> BevTracker::update(double timestamp, const std::optional<Eigen::Isometry3d>& T_world_cam_in,
                                         const std::vector<beslam_box3d>& boxes) {
  checkBoxes(boxes);
  // Time step.
  double dt = params_.default_dt;
  const double now = advanceTime(timestamp, dt);

  // Camera pose: given, extrapolated from the last two, or none (camera frame, decisions UNKNOWN).
  std::optional<Eigen::Isometry3d> T_world_cam;
  bool extrapolated = false;
  if (!takePose(now, T_world_cam_in, T_world_cam, extrapolated)) {
    // The backend has given no pose for longer than a track may coast: an extrapolated ego pose would place
    // every parked car wrongly (a lost SLAM, a long gap). Every box is unknown, and the tracks wait,
    // untouched, for the next real pose.
    std::vector<Decision> unknown(boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i)
      unknown[i].range = std::hypot(boxes[i].center_cam[0], boxes[i].center_cam[2]);
    return unknown;
  }
  last_frame_posed_ = T_world_cam_in.has_value();
  const Eigen::Isometry3d T_wc = T_world_cam ? *T_world_cam : Eigen::Isometry3d::Identity();
  const Eigen::Vector2d cam(T_wc.translation().x(), T_wc.translation().z());

  predict(dt);

  // Detections in the world BEV.
  const size_t n = boxes.size(), m = tracks_.size();
  const Placed placed = place(boxes, T_wc, now);
  const std::vector<Eigen::Vector2d>& p = placed.p;
  const std::vector<double>& range = placed.range;
  const std::vector<Eigen::Matrix2d>& cov = placed.cov;
  const std::vector<std::optional<Eigen::Vector2d>>& vel = placed.vel;

  // Cost matrix and global assignment.
  std::vector<int> det_to_track = associate(boxes, placed);

  // The parked tracks' apparent velocities, from their positions before this frame.
  references_.clear();
  if (params_.reference_tracks > 0 && T_world_cam_in)
    for (const Track& t : tracks_)
      if (t.state == BESLAM_MOTION_STATIC) {
        const Speed s = fitSpeed(t, params_.window_dynamic, std::nullopt, params_.velocity_sigma, false);
        if (s.valid) references_.push_back({t.id, s.velocity, s.sigma});
      }

  // Update matched tracks, start new ones. With an extrapolated pose a box only keeps its track alive and
  // takes its state: where the ego really went is a guess, so its position is no evidence (a guess off by a
  // metre over a second reads as a parked car moving at a metre a second), and no track starts from it.
  // The same for a box its detector doubts when uncertain_evidence is off (a car leaving the image shows a
  // shrinking part of itself, whose centre moves with what is cut, not with the car).
  std::vector<Decision> out(n);
  std::vector<char> matched(m, 0);
  auto keepImageBox = [](Track& t, const beslam_box3d& b, double time) {
    if ((b.flags & BESLAM_BOX_HAS_BBOX2D) == 0) return;
    t.bbox2d = Eigen::Vector4d(b.bbox2d[0], b.bbox2d[1], b.bbox2d[2], b.bbox2d[3]);
    t.bbox2d_t = time;
  };
  for (size_t i = 0; i < n; ++i)  // the tracks the assignment gave a box (matchByImageBox adds more)
    if (det_to_track[i] >= 0) matched[static_cast<size_t>(det_to_track[i])] = 1;
  for (size_t i = 0; i < n; ++i) {
    const beslam_box3d& b = boxes[i];
    Track* t = nullptr;
    const bool uncertain = !params_.uncertain_evidence && (b.flags & BESLAM_BOX_UNCERTAIN) != 0;
    if (uncertain && det_to_track[i] < 0) {
      det_to_track[i] = matchByImageBox(b, matched, now, dt);
      if (det_to_track[i] >= 0) matched[static_cast<size_t>(det_to_track[i])] = 1;
    }
    if (extrapolated || uncertain) {
      out[i].range = range[i];
      if (det_to_track[i] < 0) continue;
      t = &tracks_[static_cast<size_t>(det_to_track[i])];
      t->last_t = now;
      keepImageBox(*t, b, now);
      out[i].track_id = t->id;
      out[i].motion_state = T_world_cam && range[i] <= params_.max_range ? t->state : BESLAM_MOTION_UNKNOWN;
      continue;
    }
    if (det_to_track[i] >= 0) {
      t = &tracks_[static_cast<size_t>(det_to_track[i])];
      // Kalman update: position (and velocity when the detector gives one).
      if (vel[i]) {
        Eigen::Vector4d z;
        z << p[i], *vel[i];
        Eigen::Matrix4d R = Eigen::Matrix4d::Zero();
        R.topLeftCorner<2, 2>() = cov[i];
        R(2, 2) = R(3, 3) = params_.velocity_sigma * params_.velocity_sigma;
        kalmanUpdate<4>(t->x, t->P, z, R);
      } else {
        kalmanUpdate<2>(t->x, t->P, p[i], cov[i]);
      }
    } else {
      tracks_.emplace_back();
      t = &tracks_.back();
      t->id = next_id_++;
      t->x << p[i], (vel[i] ? *vel[i] : Eigen::Vector2d::Zero());
      t->P = Eigen::Matrix4d::Zero();
      t->P.topLeftCorner<2, 2>() = cov[i];
      t->P(2, 2) = t->P(3, 3) = vel[i] ? params_.velocity_sigma * params_.velocity_sigma
                                       : params_.init_velocity_sigma * params_.init_velocity_sigma;
    }
    t->class_id = carLike(b.class_id) && carLike(t->class_id) ? t->class_id : b.class_id;
    t->last_t = now;
    keepImageBox(*t, b, now);
    t->yaw_bev = placed.yaw[i];
    t->length = b.size[0] > 0 ? b.size[0] : t->length;
    t->width = b.size[1] > 0 ? b.size[1] : t->width;
    ++t->hits;
    t->history.push_back({now, p[i], cam, placed.v_sigma[i], placed.v_settling, cov[i], placed.drift_cov[i],
                          placed.line_of_sight[i].squaredNorm() == 0});
    while (static_cast<int>(t->history.size()) > params_.max_history) t->history.pop_front();

    Decision& d = out[i];
    d.track_id = t->id;
    d.range = range[i];
    // Until the poses have been watched for window_static seconds their jitter is not known: no decision yet.
    if (!params_.pose_jitter || now - first_pose_t_ >= params_.window_static - 1e-6) decide(*t, vel[i], d);
    d.motion_state = (T_world_cam && range[i] <= params_.max_range) ? t->state : BESLAM_MOTION_UNKNOWN;
  }

  dropMissed(m, matched, now, dt);
  return out;
}

std::optional<int32_t> BevTracker::parallaxEvidence(int32_t track_id, double depth_ratio) {
  for (Track& t : tracks_) {
    if (t.id != track_id) continue;
    if (!std::isfinite(depth_ratio) || std::abs(depth_ratio - 1) > params_.parallax_tolerance) {
      t.parallax_t = -1e18;  // the boxes' own speed is evidence again
      return t.state;
    }
    t.parallax_t = last_time_;
    // Contrary evidence breaks a dynamic run; the hysteresis is the speed tests' own. The parked position is
    // measured anew from here: the car's own surface says it has not moved, so how far its lifted boxes have
    // drifted since (their range error changing as the camera closes in or turns) is not a pull-out.
    ++t.static_run;
    t.dynamic_run = 0;
    t.anchor_n = 0;
    if (t.state == BESLAM_MOTION_UNKNOWN || (t.state == BESLAM_MOTION_DYNAMIC && t.static_run >= params_.stop_dwell))
      t.state = BESLAM_MOTION_STATIC;
    return t.state;
  }
  return std::nullopt;
}

void BevTracker::classify(double timestamp, const std::optional<Eigen::Isometry3d>& T_world_cam,
                          std::vector<beslam_box3d>& boxes) {
  const std::vector<Decision> d = update(timestamp, T_world_cam, boxes);
  for (size_t i = 0; i < boxes.size(); ++i) {
    boxes[i].track_id = d[i].track_id;
    boxes[i].motion_state = d[i].motion_state;
  }
}

}  // namespace beslam::motion
