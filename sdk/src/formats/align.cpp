#include "beslam/formats/align.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "beslam/formats/error.hpp"

namespace beslam::formats {

Similarity umeyama(const std::vector<Eigen::Vector3d>& p_ref, const std::vector<Eigen::Vector3d>& p_est, std::size_t n,
                   bool with_scale) {
  if (n > p_ref.size() || n > p_est.size())
    throw Error("cannot align: " + std::to_string(n) + " pairs asked of " + std::to_string(p_ref.size()) + " and " +
                std::to_string(p_est.size()) + " positions");
  Eigen::Vector3d mean_est = Eigen::Vector3d::Zero(), mean_ref = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mean_est += p_est[i];
    mean_ref += p_ref[i];
  }
  mean_est /= static_cast<double>(n);
  mean_ref /= static_cast<double>(n);

  // Umeyama (1991), eqs. 36-42: variance of the estimate, covariance ref x est.
  double variance_est = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d_est = p_est[i] - mean_est;
    const Eigen::Vector3d d_ref = p_ref[i] - mean_ref;
    variance_est += d_est.squaredNorm();
    covariance += d_ref * d_est.transpose();
  }
  variance_est /= static_cast<double>(n);
  covariance /= static_cast<double>(n);

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d d = svd.singularValues();
  const int rank = static_cast<int>((d.array() > std::numeric_limits<double>::epsilon()).count());
  if (rank < 2) {
    throw Error("cannot align: the " + std::to_string(n) + " positions used are degenerate (all equal or on one line)");
  }
  Eigen::Vector3d s = Eigen::Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s(2) = -1.0;
  Similarity out;
  out.R_ref_est = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  out.scale = with_scale ? d.dot(s) / variance_est : 1.0;
  out.t_ref_est = mean_ref - out.scale * out.R_ref_est * mean_est;
  return out;
}

PositionError positionError(const std::vector<Eigen::Vector3d>& p_est, const std::vector<Eigen::Vector3d>& p_ref) {
  PositionError r;
  r.count = p_est.size();
  if (p_est.size() < 3 || p_est.size() != p_ref.size()) return r;
  r.alignment = umeyama(p_ref, p_est, p_est.size(), true);
  double sum2 = 0, sum = 0;
  for (std::size_t i = 0; i < p_est.size(); ++i) {
    const double e = (r.alignment.apply(p_est[i]) - p_ref[i]).norm();
    sum2 += e * e;
    sum += e;
    r.max = std::max(r.max, e);
  }
  r.rmse = std::sqrt(sum2 / static_cast<double>(p_est.size()));
  r.mean = sum / static_cast<double>(p_est.size());
  return r;
}

}  // namespace beslam::formats
