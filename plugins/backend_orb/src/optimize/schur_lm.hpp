// Levenberg-Marquardt for local bundle adjustment: SE(3) poses (7 numbers [qx qy qz qw tx ty tz], left
// update as SE3LeftManifold) and 3-vectors (map points, object anchors), each residual block on one pose
// and one 3-vector, any number of rows (reprojection, ground height, object range, box centre). The
// 3-vectors are eliminated by the Schur complement; the reduced pose system is solved densely for up to
// kMaxDensePoses moving poses (local windows) and as a block-sparse system past that (global BA: a 6 x 6
// block for each pair of poses sharing a 3-vector, Eigen's simplicial Cholesky in an AMD ordering found
// once per solve).
//
// What it does per iteration: one evaluation of every residual and Jacobian (cost functions write their
// tangent Jacobian into the first six columns of the pose block, as for Ceres), robust losses by
// iteratively reweighted least squares (g2o's treatment, which ORB-SLAM2's BA uses), then damped steps
// (Marquardt's scaled diagonal, Nielsen's update of the damping, as Ceres' LM) until one lowers the cost.
// Work is split into a fixed number of 3-vector ranges whose sums are added in range order, so the result
// is the same to the bit whether the ranges run on one thread or several (OpenCV's pool).
#pragma once

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <vector>

namespace beslam::orb::optimize {

class SchurLevenbergMarquardt {
 public:
  static constexpr int kMaxDensePoses = 60;  // moving poses solved densely; more: sparse

  struct Summary {
    double initial_cost = 0, final_cost = 0;  // 0.5 * sum of rho(|r|^2), as Ceres reports it
    int iterations = 0;                       // evaluations of the Jacobians
  };

  // Blocks stay owned by the caller and are updated in place by solve().
  int addPose(double* pose, bool fixed);
  int addVector(double* x);
  // `loss` may be null (plain least squares); both stay owned by the caller.
  void addResidual(const ceres::CostFunction* cost, const ceres::LossFunction* loss, int pose, int vector);
  bool empty() const { return residuals_.empty(); }

  // At most max_iterations steps, successful or not (as Ceres counts them); it ends earlier on Ceres'
  // function and parameter tolerances (1e-6 relative cost change, 1e-8 relative step).
  Summary solve(int max_iterations);

 private:
  struct Residual {
    const ceres::CostFunction* cost;
    const ceres::LossFunction* loss;
    int pose, vector;
  };
  class Solver;  // one solve(): its layout, state and linearisation (schur_lm.cpp)

  std::vector<double*> poses_, vectors_;
  std::vector<bool> pose_fixed_;
  std::vector<Residual> residuals_;
};

}  // namespace beslam::orb::optimize
