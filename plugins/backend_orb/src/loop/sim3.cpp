#include "loop/sim3.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>

namespace beslam::orb::loop {

std::optional<Sim3> alignPoints(const std::vector<Eigen::Vector3d>& p_a, const std::vector<Eigen::Vector3d>& p_b,
                                bool fix_scale) {
  const size_t n = std::min(p_a.size(), p_b.size());
  if (n < 3) return std::nullopt;
  Eigen::Vector3d mean_a = Eigen::Vector3d::Zero(), mean_b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) mean_a += p_a[i], mean_b += p_b[i];
  mean_a /= static_cast<double>(n);
  mean_b /= static_cast<double>(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double var_a = 0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d a = p_a[i] - mean_a, b = p_b[i] - mean_b;
    cov += b * a.transpose();
    var_a += a.squaredNorm();
  }
  cov /= static_cast<double>(n);
  var_a /= static_cast<double>(n);
  if (var_a < 1e-12) return std::nullopt;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d sv = svd.singularValues();
  if (sv[1] < 1e-9 * std::max(1.0, sv[0])) return std::nullopt;  // collinear
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) D(2, 2) = -1;
  Sim3 S;
  S.R = svd.matrixU() * D * svd.matrixV().transpose();
  S.s = fix_scale ? 1.0 : (sv.asDiagonal() * D).trace() / var_a;
  if (!(S.s > 0) || !std::isfinite(S.s)) return std::nullopt;
  S.t = mean_b - S.s * S.R * mean_a;
  return S;
}

std::vector<bool> sim3Inliers(const Sim3& S_21, const std::vector<PointMatch>& matches, const PinholeIntrinsics& camera,
                              int* count) {
  constexpr double kChi2 = 9.21;  // 2 dof, 99 %
  const Sim3 S_12 = S_21.inverse();
  std::vector<bool> inliers(matches.size(), false);
  int n = 0;
  for (size_t i = 0; i < matches.size(); ++i) {
    const PointMatch& m = matches[i];
    const Eigen::Vector3d p_c2 = S_21 * m.p_c1, p_c1 = S_12 * m.p_c2;
    if (p_c2.z() <= 0 || p_c1.z() <= 0) continue;
    const double e2 = (camera.project(p_c2) - m.uv2).squaredNorm(), e1 = (camera.project(p_c1) - m.uv1).squaredNorm();
    if (e2 < kChi2 * m.sigma2_2 && e1 < kChi2 * m.sigma2_1) inliers[i] = true, ++n;
  }
  if (count) *count = n;
  return inliers;
}

std::optional<Sim3RansacResult> ransacSim3(const std::vector<PointMatch>& matches, const PinholeIntrinsics& camera,
                                           const Sim3RansacOptions& options) {
  const int n = static_cast<int>(matches.size());
  if (n < std::max(3, options.min_inliers)) return std::nullopt;
  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::optional<Sim3RansacResult> best;
  int iterations = options.max_iterations;
  for (int it = 0; it < iterations; ++it) {
    int a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    const auto S = alignPoints({matches[a].p_c1, matches[b].p_c1, matches[c].p_c1},
                               {matches[a].p_c2, matches[b].p_c2, matches[c].p_c2}, options.fix_scale);
    if (!S) continue;
    int count = 0;
    std::vector<bool> inliers = sim3Inliers(*S, matches, camera, &count);
    if (!best || count > best->inlier_count) {
      best = Sim3RansacResult{*S, std::move(inliers), count};
      // Adaptive stop: iterations that find an all-inlier minimal set with the requested probability.
      const double w = static_cast<double>(count) / n;
      const double w3 = w * w * w;
      if (w3 > 1e-9 && w3 < 1.0) {
        const double needed = std::log(1.0 - options.probability) / std::log(1.0 - w3);
        iterations = std::min(options.max_iterations, std::max(it + 1, static_cast<int>(std::ceil(needed))));
      } else if (w3 >= 1.0) {
        break;
      }
    }
  }
  if (!best || best->inlier_count < options.min_inliers) return std::nullopt;
  // Refit on the inliers, keep the refit if it does not lose inliers.
  std::vector<Eigen::Vector3d> p1, p2;
  for (int i = 0; i < n; ++i)
    if (best->inliers[i]) p1.push_back(matches[i].p_c1), p2.push_back(matches[i].p_c2);
  if (const auto refit = alignPoints(p1, p2, options.fix_scale)) {
    int count = 0;
    std::vector<bool> inliers = sim3Inliers(*refit, matches, camera, &count);
    if (count >= best->inlier_count) *best = Sim3RansacResult{*refit, std::move(inliers), count};
  }
  return best;
}

}  // namespace beslam::orb::loop
