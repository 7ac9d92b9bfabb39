#include "optimize/pose_optimizer.hpp"

#include <ceres/loss_function.h>

#include <Eigen/Cholesky>
#include <cmath>

#include "optimize/cost_functions.hpp"
#include "optimize/lm_damping.hpp"
#include "optimize/se3.hpp"

namespace beslam::orb::optimize {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// The observations of one round (the outliers of the last round left out) against one pose.
class PoseProblem {
 public:
  PoseProblem(const Intrinsics& K, const std::vector<PoseObservation>& observations, const std::vector<bool>& outlier,
              const ceres::LossFunction* loss)
      : K_(K), observations_(observations), outlier_(outlier), loss_(loss) {}

  // 0.5 * sum of rho(|r|^2) at `pose`; with H and g, the normal equations of the robustly reweighted
  // residuals (H = sum w J^T J, g = sum w J^T r, w = rho'), J on the pose's left tangent.
  double evaluate(const double* pose, Matrix6d* H = nullptr, Vector6d* g = nullptr) const {
    if (H) H->setZero();
    if (g) g->setZero();
    double cost = 0, r[2], J[2 * 7];
    Eigen::Vector3d pc;
    Eigen::Matrix<double, 2, 3> J_proj;
    Eigen::Matrix3d R;
    for (size_t i = 0; i < observations_.size(); ++i) {
      if (outlier_[i]) continue;
      const PoseObservation& o = observations_[i];
      detail::reproject(pose, o.point_world, K_, o.pixel, o.inv_sigma, r, pc, J_proj, R, H != nullptr);
      const double sq = r[0] * r[0] + r[1] * r[1];
      double rho[3] = {sq, 1, 0};
      if (loss_) loss_->Evaluate(sq, rho);
      cost += 0.5 * rho[0];
      if (!H) continue;
      detail::poseJacobian<2>(J_proj, pc, J);
      for (int row = 0; row < 2; ++row) {
        const Eigen::Map<const Vector6d> j(&J[7 * row]);  // the tangent part: the first six columns
        H->noalias() += rho[1] * j * j.transpose();
        *g += (rho[1] * r[row]) * j;
      }
    }
    return cost;
  }

 private:
  const Intrinsics& K_;
  const std::vector<PoseObservation>& observations_;
  const std::vector<bool>& outlier_;
  const ceres::LossFunction* loss_;
};

// Levenberg-Marquardt on the 6-dof pose (the step control of lm_damping.hpp): at most `iterations` steps,
// successful or not, as Ceres counts them.
void solve(const PoseProblem& problem, double* pose, int iterations) {
  Matrix6d H, H_try;
  Vector6d g, g_try;
  double cost = problem.evaluate(pose, &H, &g);
  lm::Damping damping;
  double pose_try[7];
  for (int step = 0; step < iterations; ++step) {
    Matrix6d A = H;
    Vector6d D;
    for (int d = 0; d < 6; ++d) {
      D(d) = lm::clampDiagonal(H(d, d));
      A(d, d) += damping.mu * D(d);
    }
    const Eigen::LLT<Matrix6d> llt(A);
    Vector6d dp = Vector6d::Zero();
    bool solved = llt.info() == Eigen::Success;
    if (solved) {
      dp = llt.solve(-g);
      solved = dp.allFinite();
    }
    // The linear model's predicted decrease 0.5 (-g.d + mu d.D.d), as Ceres' LM.
    const double predicted = solved ? 0.5 * (-g.dot(dp) + damping.mu * dp.dot(D.cwiseProduct(dp))) : 0;
    double new_cost = cost;
    if (solved && predicted > 0) {
      SE3LeftManifold().Plus(pose, dp.data(), pose_try);
      // Linearised at the candidate too: most steps are taken, and their next system is this one.
      new_cost = problem.evaluate(pose_try, &H_try, &g_try);
      // Ceres' convergence tests on the candidate before it is accepted: it is dropped and the solve ends.
      double x_sq = 0;
      for (int i = 0; i < 7; ++i) x_sq += pose[i] * pose[i];
      if (lm::converged(dp.norm(), std::sqrt(x_sq), cost, new_cost)) break;
    }
    const double rho = solved && predicted > 0 ? (cost - new_cost) / predicted : -1;
    if (std::isfinite(new_cost) && rho > lm::kMinRelativeDecrease) {
      std::copy(pose_try, pose_try + 7, pose);
      damping.accepted(rho);
      if (step + 1 == iterations) break;
      cost = new_cost;
      H = H_try;
      g = g_try;
    } else if (!damping.refused()) {
      break;
    }
  }
}

}  // namespace

int optimizePose(const Camera& camera, const std::vector<PoseObservation>& observations, Eigen::Isometry3d& T_cw,
                 std::vector<bool>& outlier, const PoseOptimizerOptions& options) {
  const size_t n = observations.size();
  outlier.assign(n, false);
  if (n < 3) return 0;
  const Intrinsics K{camera.fx, camera.fy, camera.cx, camera.cy};
  const ceres::HuberLoss huber(std::sqrt(options.chi2_threshold));

  double pose[7];
  poseToParams(T_cw, pose);
  int inliers = 0;
  for (int round = 0; round < options.rounds; ++round) {
    int used = 0;
    for (size_t i = 0; i < n; ++i) used += !outlier[i];
    if (used < 3) break;
    const bool robust = round < 2;  // later rounds without the robust loss, outliers already out
    solve(PoseProblem(K, observations, outlier, robust ? &huber : nullptr), pose, options.iterations);

    inliers = 0;
    double r[2];
    Eigen::Vector3d pc;
    Eigen::Matrix<double, 2, 3> J_proj;
    Eigen::Matrix3d R;
    for (size_t i = 0; i < n; ++i) {
      const PoseObservation& o = observations[i];
      detail::reproject(pose, o.point_world, K, o.pixel, o.inv_sigma, r, pc, J_proj, R, false);
      outlier[i] = r[0] * r[0] + r[1] * r[1] > options.chi2_threshold;
      if (!outlier[i]) ++inliers;
    }
    if (inliers < 10) break;
  }
  T_cw = paramsToPose(pose);
  return inliers;
}

}  // namespace beslam::orb::optimize
