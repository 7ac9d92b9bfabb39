// Paths (cubic B-splines by arc length), speed profiles, RNG helpers.
#include <algorithm>
#include <cmath>

#include "world.hpp"

namespace beslam::sim::detail {

double Rng::normal() {
  // Box-Muller on our own uniforms (portable).
  double u1 = uniform();
  if (u1 < 1e-300) u1 = 1e-300;
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

static double wrapAngle(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a < -M_PI) a += 2 * M_PI;
  return a;
}

Path::Path(const std::vector<Vec2d>& control_in, bool closed) : closed_(closed) {
  std::vector<Vec2d> c;
  if (closed) {
    c = control_in;
  } else {
    c.push_back(control_in.front());
    c.push_back(control_in.front());
    c.insert(c.end(), control_in.begin(), control_in.end());
    c.push_back(control_in.back());
    c.push_back(control_in.back());
  }
  const int n = static_cast<int>(c.size());
  const int segments = closed ? n : n - 3;
  const int per = 8;
  auto P = [&](int i) -> const Vec2d& { return c[((i % n) + n) % n]; };
  double s = 0;
  Vec2d prev(0, 0);
  for (int seg = 0; seg < segments; ++seg) {
    const int base = closed ? seg - 1 : seg;
    const Vec2d &p0 = P(base), &p1 = P(base + 1), &p2 = P(base + 2), &p3 = P(base + 3);
    for (int k = 0; k < per || (seg == segments - 1 && k == per); ++k) {
      const double t = static_cast<double>(k) / per, u = 1 - t;
      const Vec2d p = (u * u * u * p0 + (3 * t * t * t - 6 * t * t + 4) * p1 +
                       (-3 * t * t * t + 3 * t * t + 3 * t + 1) * p2 + t * t * t * p3) /
                      6.0;
      const Vec2d d1 = (-u * u * p0 + (3 * t * t - 4 * t) * p1 + (-3 * t * t + 2 * t + 1) * p2 + t * t * p3) / 2.0;
      const Vec2d d2 = u * p0 + (3 * t - 2) * p1 + (1 - 3 * t) * p2 + t * p3;
      if (!s_.empty()) s += (p - prev).norm();
      prev = p;
      const double speed = std::max(d1.norm(), 1e-9);
      s_.push_back(s);
      x_.push_back(p.x());
      y_.push_back(p.y());
      heading_.push_back(std::atan2(d1.y(), d1.x()));
      curvature_.push_back((d1.x() * d2.y() - d1.y() * d2.x()) / (speed * speed * speed));
    }
  }
  if (closed) {  // close the loop exactly
    s += std::hypot(x_.front() - x_.back(), y_.front() - y_.back());
    s_.push_back(s);
    x_.push_back(x_.front());
    y_.push_back(y_.front());
    heading_.push_back(heading_.front());
    curvature_.push_back(curvature_.front());
  }
  length_ = s;
}

void Path::at(double s, Vec2d& p, double& heading, double& curvature) const {
  if (closed_) {
    s = std::fmod(s, length_);
    if (s < 0) s += length_;
  } else {
    s = std::clamp(s, 0.0, length_);
  }
  auto it = std::upper_bound(s_.begin(), s_.end(), s);
  std::size_t i = it == s_.begin() ? 0 : static_cast<std::size_t>(it - s_.begin()) - 1;
  if (i + 1 >= s_.size()) i = s_.size() - 2;
  const double span = s_[i + 1] - s_[i];
  const double f = span > 1e-12 ? (s - s_[i]) / span : 0.0;
  p = Vec2d(x_[i] + f * (x_[i + 1] - x_[i]), y_[i] + f * (y_[i + 1] - y_[i]));
  heading = wrapAngle(heading_[i] + f * wrapAngle(heading_[i + 1] - heading_[i]));
  curvature = curvature_[i] + f * (curvature_[i + 1] - curvature_[i]);
}

Profile::Profile(const Path& path, double v_cruise, double a_lat, double a_long, double v_start, double v_end)
    : closed_(path.closed()), length_(path.length()) {
  const double ds = 0.5;
  const int n = std::max(2, static_cast<int>(std::ceil(length_ / ds)) + 1);
  const int laps = closed_ ? 3 : 1;
  const int m = closed_ ? (n - 1) * laps + 1 : n;
  const double step = length_ / (n - 1);
  std::vector<double> v(m);
  for (int i = 0; i < m; ++i) {
    Vec2d p;
    double h, k;
    path.at(closed_ ? (i % (n - 1)) * step : i * step, p, h, k);
    v[i] = std::min(v_cruise, std::sqrt(a_lat / std::max(std::abs(k), 1e-9)));
  }
  if (!closed_) {
    if (v_start >= 0) v[0] = std::min(v[0], v_start);
    if (v_end >= 0) v[m - 1] = std::min(v[m - 1], v_end);
  }
  for (int i = 1; i < m; ++i) v[i] = std::min(v[i], std::sqrt(v[i - 1] * v[i - 1] + 2 * a_long * step));
  for (int i = m - 2; i >= 0; --i) v[i] = std::min(v[i], std::sqrt(v[i + 1] * v[i + 1] + 2 * a_long * step));
  const int first = closed_ ? n - 1 : 0;  // the middle lap of a closed path
  s_.resize(n);
  v_.resize(n);
  t_.resize(n);
  for (int i = 0; i < n; ++i) {
    s_[i] = i * step;
    v_[i] = v[first + i];
  }
  t_[0] = 0;
  for (int i = 1; i < n; ++i) {
    const double vm = std::max(0.5 * (v_[i] + v_[i - 1]), 1e-3);
    t_[i] = t_[i - 1] + step / vm;
  }
}

double Profile::sAt(double t) const {
  if (t <= 0 || t_.empty()) return 0;
  const double T = t_.back();
  double base = 0;
  if (closed_) {
    const double laps = std::floor(t / T);
    base = laps * length_;
    t -= laps * T;
  } else if (t >= T) {
    return length_;
  }
  auto it = std::upper_bound(t_.begin(), t_.end(), t);
  std::size_t i = it == t_.begin() ? 0 : static_cast<std::size_t>(it - t_.begin()) - 1;
  if (i + 1 >= t_.size()) i = t_.size() - 2;
  // Constant acceleration within a cell.
  const double tau = t - t_[i], dt = t_[i + 1] - t_[i];
  const double a = dt > 0 ? (v_[i + 1] - v_[i]) / dt : 0;
  const double ds = std::min(v_[i] * tau + 0.5 * a * tau * tau, s_[i + 1] - s_[i]);
  return base + s_[i] + std::max(0.0, ds);
}

double Profile::speedAt(double t) const {
  if (t_.empty()) return 0;
  const double T = t_.back();
  if (closed_)
    t -= std::floor(t / T) * T;
  else if (t < 0 || t >= T)
    return 0;
  auto it = std::upper_bound(t_.begin(), t_.end(), t);
  std::size_t i = it == t_.begin() ? 0 : static_cast<std::size_t>(it - t_.begin()) - 1;
  if (i + 1 >= t_.size()) i = t_.size() - 2;
  const double dt = t_[i + 1] - t_[i];
  const double f = dt > 0 ? (t - t_[i]) / dt : 0;
  return v_[i] + f * (v_[i + 1] - v_[i]);
}

}  // namespace beslam::sim::detail
