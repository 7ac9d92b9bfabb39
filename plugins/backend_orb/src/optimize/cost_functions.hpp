// Reprojection errors with analytic Jacobians, whitened by the keypoint level's sigma
// (residual = (projection - observation) / sigma, so the squared norm is the chi-square statistic).
#pragma once

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace beslam::orb::optimize {

struct Intrinsics {
  double fx, fy, cx, cy;
};

namespace detail {
// p_c = R p_w + t and the whitened residual; J_proj = d residual / d p_c.
// p_c = R p_w + t for a pose block [qx qy qz qw tx ty tz]; R is returned for the point Jacobian.
inline Eigen::Vector3d toCamera(const double* pose, const Eigen::Vector3d& pw, Eigen::Matrix3d& R) {
  R = Eigen::Quaterniond(pose[3], pose[0], pose[1], pose[2]).toRotationMatrix();
  return R * pw + Eigen::Vector3d(pose[4], pose[5], pose[6]);
}

inline bool reproject(const double* pose, const Eigen::Vector3d& pw, const Intrinsics& K, const Eigen::Vector2d& obs,
                      double inv_sigma, double* residual, Eigen::Vector3d& pc, Eigen::Matrix<double, 2, 3>& J_proj,
                      Eigen::Matrix3d& R, bool need_jacobian) {
  pc = toCamera(pose, pw, R);
  double z = pc.z();
  if (std::abs(z) < 1e-6) z = z < 0 ? -1e-6 : 1e-6;
  const double iz = 1.0 / z;
  residual[0] = (K.fx * pc.x() * iz + K.cx - obs.x()) * inv_sigma;
  residual[1] = (K.fy * pc.y() * iz + K.cy - obs.y()) * inv_sigma;
  if (need_jacobian) {
    J_proj << K.fx * iz, 0, -K.fx * pc.x() * iz * iz, 0, K.fy * iz, -K.fy * pc.y() * iz * iz;
    J_proj *= inv_sigma;
  }
  return true;
}

// The Jacobian on the pose's left tangent [rho, phi] (d pc = rho + phi x pc) of a residual whose Jacobian on
// the camera-frame point pc is J_pc (rows x 3); the 7th column (the quaternion's 4th number) is zero.
template <int Rows>
void poseJacobian(const Eigen::Matrix<double, Rows, 3>& J_pc, const Eigen::Vector3d& pc, double* out) {
  Eigen::Map<Eigen::Matrix<double, Rows, 7, Eigen::RowMajor>> J(out);
  Eigen::Matrix3d skew;
  skew << 0, -pc.z(), pc.y(), pc.z(), 0, -pc.x(), -pc.y(), pc.x(), 0;
  J.template leftCols<3>() = J_pc;
  J.template block<Rows, 3>(0, 3) = -J_pc * skew;
  J.col(6).setZero();
}

// A Jacobian block into Ceres' row-major array.
template <int Rows, int Cols>
void writeJacobian(const Eigen::Matrix<double, Rows, Cols>& J, double* out) {
  Eigen::Map<Eigen::Matrix<double, Rows, Cols, Eigen::RowMajor>> m(out);
  m = J;
}
}  // namespace detail

// Bundle adjustment: pose and point.
class ReprojectionCost : public ceres::SizedCostFunction<2, 7, 3> {
 public:
  ReprojectionCost(const Eigen::Vector2d& obs, double inv_sigma, const Intrinsics& K)
      : obs_(obs), inv_sigma_(inv_sigma), K_(K) {}
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    Eigen::Vector3d pc;
    Eigen::Matrix<double, 2, 3> J_proj;
    Eigen::Matrix3d R;
    const bool need = jacobians && (jacobians[0] || jacobians[1]);
    detail::reproject(params[0], Eigen::Vector3d(params[1][0], params[1][1], params[1][2]), K_, obs_, inv_sigma_,
                      residuals, pc, J_proj, R, need);
    if (need && jacobians[0]) detail::poseJacobian(J_proj, pc, jacobians[0]);
    if (need && jacobians[1]) detail::writeJacobian<2, 3>(J_proj * R, jacobians[1]);
    return true;
  }

 private:
  Eigen::Vector2d obs_;
  double inv_sigma_;
  Intrinsics K_;
};

// Ground prior: a ground point's height below the keyframe's camera, along the keyframe's fitted plane
// normal n (camera frame, held constant), should be the reference camera height h:
// residual = (n . (R p_w + t) - h) / sigma.
class GroundHeightCost : public ceres::SizedCostFunction<1, 7, 3> {
 public:
  GroundHeightCost(const Eigen::Vector3d& normal_cam, double height, double sigma)
      : n_(normal_cam), h_(height), inv_sigma_(1.0 / sigma) {}
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    Eigen::Matrix3d R;
    const Eigen::Vector3d pc =
        detail::toCamera(params[0], Eigen::Vector3d(params[1][0], params[1][1], params[1][2]), R);
    residuals[0] = (n_.dot(pc) - h_) * inv_sigma_;
    if (jacobians && jacobians[0]) {  // tangent [rho, phi] of the left update: d pc = rho + phi x pc
      Eigen::Map<Eigen::Matrix<double, 1, 7, Eigen::RowMajor>> J(jacobians[0]);
      J.leftCols<3>() = n_.transpose() * inv_sigma_;
      J.block<1, 3>(0, 3) = pc.cross(n_).transpose() * inv_sigma_;
      J(0, 6) = 0;
    }
    if (jacobians && jacobians[1]) {
      Eigen::Map<Eigen::Matrix<double, 1, 3, Eigen::RowMajor>> Jp(jacobians[1]);
      Jp = n_.transpose() * R * inv_sigma_;
    }
    return true;
  }

 private:
  Eigen::Vector3d n_;
  double h_, inv_sigma_;
};

// A metric range prior: the distance of a point from the camera, along the ray of its keypoint, is where
// that ray enters the metric 3D box of the static object the keypoint lies on (ObjectBox). Residual in
// sigmas: (|p_cam| - range) / sigma.
class ObjectRangeCost : public ceres::SizedCostFunction<1, 7, 3> {
 public:
  ObjectRangeCost(double range, double sigma) : d_(range), inv_sigma_(1.0 / sigma) {}
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    Eigen::Matrix3d R;
    const Eigen::Vector3d pc =
        detail::toCamera(params[0], Eigen::Vector3d(params[1][0], params[1][1], params[1][2]), R);
    const double r = pc.norm();
    residuals[0] = (r - d_) * inv_sigma_;
    const Eigen::Vector3d u = r > 1e-12 ? Eigen::Vector3d(pc / r) : Eigen::Vector3d::UnitZ();
    if (jacobians && jacobians[0]) {  // d|pc| = u . (rho + phi x pc) = u . rho (u is parallel to pc)
      Eigen::Map<Eigen::Matrix<double, 1, 7, Eigen::RowMajor>> J(jacobians[0]);
      J.setZero();
      J.leftCols<3>() = u.transpose() * inv_sigma_;
    }
    if (jacobians && jacobians[1]) {
      Eigen::Map<Eigen::Matrix<double, 1, 3, Eigen::RowMajor>> Jp(jacobians[1]);
      Jp = u.transpose() * R * inv_sigma_;
    }
    return true;
  }

 private:
  double d_, inv_sigma_;
};

// A parked car's box centre as a metric 3D measurement: the camera sees the car's anchor p_world (one per
// parked track, the box centre in the world) at b_cam, the centre of its metric 3D box in this frame.
// Residual in sigmas: (T_cw p_world - b_cam) / sigma. Unlike ObjectRangeCost it does not depend on how a
// car fills its box, only on the detector's centre.
class BoxCentreCost : public ceres::SizedCostFunction<3, 7, 3> {
 public:
  BoxCentreCost(const Eigen::Vector3d& b_cam, double sigma) : b_(b_cam), inv_sigma_(1.0 / sigma) {}
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    Eigen::Matrix3d R;
    const Eigen::Vector3d pc =
        detail::toCamera(params[0], Eigen::Vector3d(params[1][0], params[1][1], params[1][2]), R);
    Eigen::Map<Eigen::Vector3d> r(residuals);
    r = (pc - b_) * inv_sigma_;
    const Eigen::Matrix3d J_pc = Eigen::Matrix3d::Identity() * inv_sigma_;
    if (jacobians && jacobians[0]) detail::poseJacobian<3>(J_pc, pc, jacobians[0]);
    if (jacobians && jacobians[1]) detail::writeJacobian<3, 3>(J_pc * R, jacobians[1]);
    return true;
  }

 private:
  Eigen::Vector3d b_;
  double inv_sigma_;
};

}  // namespace beslam::orb::optimize
