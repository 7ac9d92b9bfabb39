// Trajectory alignment and the absolute position error, as evo defines them (Umeyama 1991 on positions):
// p_ref = scale * R_ref_est * p_est + t_ref_est, least squares over the pairs given (pair i with i).
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

namespace beslam::formats {

struct Similarity {
  double scale = 1.0;
  Eigen::Matrix3d R_ref_est = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_ref_est = Eigen::Vector3d::Zero();
  Eigen::Vector3d apply(const Eigen::Vector3d& p_est) const { return scale * (R_ref_est * p_est) + t_ref_est; }
};

// Fits the first n pairs (n <= both sizes). with_scale false: scale 1 (SE(3)). Throws beslam::Error when
// n is 0 or the positions are degenerate (fewer than 2 non-zero singular values of the covariance, as evo).
Similarity umeyama(const std::vector<Eigen::Vector3d>& p_ref, const std::vector<Eigen::Vector3d>& p_est, std::size_t n,
                   bool with_scale);

// Translation APE after a Sim(3) fit of all pairs (sizes must match): RMSE, mean and largest error in the
// reference's units. Fewer than 3 pairs, or sizes that differ: count only, errors 0, identity alignment.
struct PositionError {
  double rmse = 0, mean = 0, max = 0;
  std::size_t count = 0;
  Similarity alignment;
};
PositionError positionError(const std::vector<Eigen::Vector3d>& p_est, const std::vector<Eigen::Vector3d>& p_ref);

}  // namespace beslam::formats
