// Absolute pose error after a Sim(3) (Umeyama) alignment of estimated positions to ground truth.
// A small self-contained helper for this module's tool and tests (the platform has its own evaluator).
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Dense>

namespace beslam::orb::eval {

struct Sim3 {
  double scale = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return scale * (R * p) + t; }
};

// Least-squares s, R, t minimising sum |dst - (s R src + t)|^2 (Umeyama 1991).
inline Sim3 umeyama(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                    bool with_scale = true) {
  const size_t n = src.size();
  Eigen::Vector3d ms = Eigen::Vector3d::Zero(), md = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    ms += src[i];
    md += dst[i];
  }
  ms /= static_cast<double>(n);
  md /= static_cast<double>(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double var_s = 0;
  for (size_t i = 0; i < n; ++i) {
    cov += (dst[i] - md) * (src[i] - ms).transpose();
    var_s += (src[i] - ms).squaredNorm();
  }
  cov /= static_cast<double>(n);
  var_s /= static_cast<double>(n);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  Sim3 out;
  out.R = svd.matrixU() * S * svd.matrixV().transpose();
  out.scale = with_scale && var_s > 0 ? (svd.singularValues().asDiagonal() * S).trace() / var_s : 1.0;
  out.t = md - out.scale * out.R * ms;
  return out;
}

struct ApeResult {
  double rmse = 0, mean = 0, max = 0;
  size_t count = 0;
  Sim3 alignment;
};

inline ApeResult apeTranslation(const std::vector<Eigen::Vector3d>& estimate,
                                const std::vector<Eigen::Vector3d>& truth) {
  ApeResult r;
  r.count = estimate.size();
  if (estimate.size() < 3 || estimate.size() != truth.size()) return r;
  r.alignment = umeyama(estimate, truth, true);
  double sum2 = 0, sum = 0;
  for (size_t i = 0; i < estimate.size(); ++i) {
    const double e = (r.alignment.apply(estimate[i]) - truth[i]).norm();
    sum2 += e * e;
    sum += e;
    r.max = std::max(r.max, e);
  }
  r.rmse = std::sqrt(sum2 / static_cast<double>(estimate.size()));
  r.mean = sum / static_cast<double>(estimate.size());
  return r;
}

}  // namespace beslam::orb::eval
