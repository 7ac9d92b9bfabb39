#include "ground/ground_plane.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "map/keyframe.hpp"
#include "map/map_point.hpp"

namespace beslam::orb {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Plane n . p = h through three points, n on the side of `down`; false if degenerate or too tilted.
bool planeFrom(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
               const Eigen::Vector3d& down, double min_cos_tilt, Eigen::Vector3d* n, double* h) {
  Eigen::Vector3d v = (b - a).cross(c - a);
  const double len = v.norm();
  if (len < 1e-12) return false;
  v /= len;
  if (v.dot(down) < 0) v = -v;
  if (v.dot(down) < min_cos_tilt) return false;
  *n = v;
  *h = v.dot(a);
  return *h > 0;
}

int countInliers(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& n, double h, double ratio,
                 std::vector<int>* inliers) {
  if (inliers) inliers->clear();
  int count = 0;
  const double tol = ratio * h;
  for (size_t i = 0; i < pts.size(); ++i)
    if (std::abs(n.dot(pts[i]) - h) < tol) {
      ++count;
      if (inliers) inliers->push_back(static_cast<int>(i));
    }
  return count;
}

}  // namespace

double median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

double medianAbsoluteDeviation(const std::vector<double>& values, double m) {
  std::vector<double> deviations;
  deviations.reserve(values.size());
  for (double x : values) deviations.push_back(std::abs(x - m));
  return median(std::move(deviations));
}

std::optional<GroundPlane> fitGroundPlane(const KeyFrame& kf, const GroundPlaneOptions& options,
                                          const Eigen::Vector3d& expected_normal_cam, double max_tilt_deg) {
  const Eigen::Vector3d down = expected_normal_cam.normalized();
  std::vector<Eigen::Vector3d> pts;
  std::vector<MapPoint*> owners;
  std::set<const MapPoint*> taken;
  // Points under the horizon of the keyframe `seen_by` (its own down direction: the same world direction),
  // in kf's camera frame.
  auto collect = [&](const KeyFrame& seen_by) {
    const Eigen::Matrix3d R_seen_kf = seen_by.T_cw.linear() * kf.T_cw.linear().transpose();
    const Eigen::Vector3d down_seen = R_seen_kf * down;
    for (MapPoint* mp : seen_by.validPoints()) {
      const Eigen::Vector3d p_seen = seen_by.T_cw * mp->position;
      if (p_seen.z() <= 0 || down_seen.dot(p_seen) < options.min_ray_below_horizon * p_seen.z()) continue;
      if (!taken.insert(mp).second && &seen_by != &kf) continue;  // (the keyframe's own list as it is)
      pts.push_back(kf.T_cw * mp->position);
      owners.push_back(mp);
    }
  };
  collect(kf);
  if (options.pool_keyframes > 0)  // the road the camera drove over since, or will: planar over a few metres
    for (const KeyFrame* n : kf.covisibles())
      if (!n->bad && n != &kf && std::abs(n->id - kf.id) <= options.pool_keyframes) collect(*n);
  if (static_cast<int>(pts.size()) < options.min_inliers) return std::nullopt;

  const double min_cos_tilt = std::cos(max_tilt_deg * kPi / 180.0);
  std::mt19937 rng(static_cast<uint32_t>(kf.id) * 2654435761u + 17u);
  std::uniform_int_distribution<size_t> pick(0, pts.size() - 1);
  int best = 0;
  Eigen::Vector3d best_n = Eigen::Vector3d::UnitY();
  double best_h = 0;
  for (int it = 0; it < options.ransac_iterations; ++it) {
    const size_t i = pick(rng), j = pick(rng), k = pick(rng);
    if (i == j || j == k || i == k) continue;
    Eigen::Vector3d n;
    double h;
    if (!planeFrom(pts[i], pts[j], pts[k], down, min_cos_tilt, &n, &h)) continue;
    const int count = countInliers(pts, n, h, options.inlier_ratio, nullptr);
    if (count > best) {
      best = count;
      best_n = n;
      best_h = h;
    }
  }
  if (best < options.min_inliers) return std::nullopt;

  // Least-squares refinement on the inliers (smallest principal axis through their centroid), then the
  // inliers of the refined plane.
  std::vector<int> in;
  countInliers(pts, best_n, best_h, options.inlier_ratio, &in);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int i : in) centroid += pts[i];
  centroid /= static_cast<double>(in.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : in) cov += (pts[i] - centroid) * (pts[i] - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  if (n.dot(down) < 0) n = -n;
  const double h = n.dot(centroid);
  if (n.dot(down) >= min_cos_tilt && h > 0 &&
      countInliers(pts, n, h, options.inlier_ratio, nullptr) >= options.min_inliers) {
    best_n = n;
    best_h = h;
  }
  countInliers(pts, best_n, best_h, options.inlier_ratio, &in);
  if (static_cast<int>(in.size()) < options.min_inliers) return std::nullopt;
  GroundPlane plane;
  plane.normal_cam = best_n;
  plane.height = best_h;
  for (int i : in) plane.inliers.push_back(owners[i]);
  return plane;
}

void GroundReference::add(double value, const Eigen::Vector3d& normal) {
  if (ready_ || !(value > 0) || !std::isfinite(value) || !normal.allFinite()) return;
  heights_.push_back(value);
  normals_.push_back(normal);
  if (static_cast<int>(heights_.size()) > needed_) {  // slide: the oldest fit leaves the window
    heights_.erase(heights_.begin());
    normals_.erase(normals_.begin());
  }
  if (static_cast<int>(heights_.size()) < needed_) return;
  const double h = median(heights_);
  const double spread = medianAbsoluteDeviation(heights_, h) / h;
  if (spread > max_spread_) return;
  height_ = h;
  spread_ = spread;
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
  for (const auto& n : normals_) normal_sum += n;
  normal_ = normal_sum.normalized();
  ready_ = true;
}

}  // namespace beslam::orb
