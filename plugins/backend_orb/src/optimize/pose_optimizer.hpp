// Pose-only optimisation (motion-only BA): the camera pose against fixed map points, reprojection
// errors weighted by 1 / level variance, Huber (sqrt 5.991) in the first two rounds, four rounds of 10
// iterations; after each round observations above chi-square 5.991 become outliers and sit out the next
// round (they may come back). Each round is Levenberg-Marquardt on the pose's 6-vector with the step
// control of lm_damping.hpp (Ceres' LM) and the robust loss as reweighting (g2o's treatment, as in
// ORB-SLAM2): the 6 x 6 normal equations are summed directly, with no per-call solver set-up.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "beslam_orb/options.hpp"

namespace beslam::orb::optimize {

struct PoseObservation {
  Eigen::Vector3d point_world;
  Eigen::Vector2d pixel;
  double inv_sigma = 1.0;  // 1 / (level scale), times sqrt(weight) for trusted points
};

struct PoseOptimizerOptions {
  int rounds = 4;
  int iterations = 10;
  double chi2_threshold = 5.991;
};

// Optimises T_cw in place; outlier[i] tells the final classification. Returns the inlier count.
int optimizePose(const Camera& camera, const std::vector<PoseObservation>& observations, Eigen::Isometry3d& T_cw,
                 std::vector<bool>& outlier, const PoseOptimizerOptions& options = {});

}  // namespace beslam::orb::optimize
