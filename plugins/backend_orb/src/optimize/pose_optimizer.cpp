#include "optimize/pose_optimizer.hpp"

#include <ceres/ceres.h>

#include <cmath>
#include <memory>

#include "optimize/cost_functions.hpp"
#include "optimize/se3.hpp"

namespace beslam::orb::optimize {

int optimizePose(const Camera& camera, const std::vector<PoseObservation>& observations, Eigen::Isometry3d& T_cw,
                 std::vector<bool>& outlier, const PoseOptimizerOptions& options) {
  const size_t n = observations.size();
  outlier.assign(n, false);
  if (n < 3) return 0;
  const Intrinsics K{camera.fx, camera.fy, camera.cx, camera.cy};
  std::vector<std::unique_ptr<PoseReprojectionCost>> costs;
  costs.reserve(n);
  for (const auto& o : observations)
    costs.push_back(std::make_unique<PoseReprojectionCost>(o.point_world, o.pixel, o.inv_sigma, K));
  ceres::HuberLoss huber(std::sqrt(options.chi2_threshold));
  SE3LeftManifold manifold;

  double pose[7];
  poseToParams(T_cw, pose);
  int inliers = 0;
  for (int round = 0; round < options.rounds; ++round) {
    ceres::Problem::Options popts;
    popts.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    popts.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    popts.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(popts);
    problem.AddParameterBlock(pose, 7, &manifold);
    const bool robust = round < 2;  // later rounds without the robust loss, outliers already out
    int used = 0;
    for (size_t i = 0; i < n; ++i) {
      if (outlier[i]) continue;
      problem.AddResidualBlock(costs[i].get(), robust ? &huber : nullptr, pose);
      ++used;
    }
    if (used < 3) break;
    ceres::Solver::Options sopts;
    sopts.linear_solver_type = ceres::DENSE_QR;
    sopts.max_num_iterations = options.iterations;
    sopts.logging_type = ceres::SILENT;
    sopts.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(sopts, &problem, &summary);

    inliers = 0;
    for (size_t i = 0; i < n; ++i) {
      double r[2];
      const double* params[] = {pose};
      costs[i]->Evaluate(params, r, nullptr);
      const double chi2 = r[0] * r[0] + r[1] * r[1];
      outlier[i] = chi2 > options.chi2_threshold;
      if (!outlier[i]) ++inliers;
    }
    if (inliers < 10) break;
  }
  T_cw = paramsToPose(pose);
  return inliers;
}

}  // namespace beslam::orb::optimize
