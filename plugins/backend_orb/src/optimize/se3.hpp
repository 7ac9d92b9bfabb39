// Poses as Ceres parameter blocks: 7 doubles [qx qy qz qw tx ty tz] for T_cw, updated on the left
// (T <- exp(delta) T, delta = [rho, phi]). Cost functions write their 2 x 6 tangent Jacobian into the
// first six columns of the 2 x 7 block; the manifold's Plus Jacobian is [I6; 0], so Ceres sees exactly
// the tangent Jacobian.
#pragma once

#include <ceres/manifold.h>

#include <Eigen/Geometry>
#include <cmath>

namespace beslam::orb::optimize {

inline void poseToParams(const Eigen::Isometry3d& T, double* p) {
  const Eigen::Quaterniond q(T.linear());
  p[0] = q.x();
  p[1] = q.y();
  p[2] = q.z();
  p[3] = q.w();
  p[4] = T.translation().x();
  p[5] = T.translation().y();
  p[6] = T.translation().z();
}

inline Eigen::Isometry3d paramsToPose(const double* p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p[3], p[0], p[1], p[2]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(p[4], p[5], p[6]);
  return T;
}

inline Eigen::Quaterniond expSO3(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, phi / angle));
}

class SE3LeftManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus) const override {
    const Eigen::Quaterniond q(x[3], x[0], x[1], x[2]);
    const Eigen::Vector3d t(x[4], x[5], x[6]);
    const Eigen::Vector3d rho(delta[0], delta[1], delta[2]), phi(delta[3], delta[4], delta[5]);
    const Eigen::Quaterniond dq = expSO3(phi);
    const Eigen::Quaterniond q2 = (dq * q).normalized();
    const Eigen::Vector3d t2 = dq * t + rho;
    x_plus[0] = q2.x();
    x_plus[1] = q2.y();
    x_plus[2] = q2.z();
    x_plus[3] = q2.w();
    x_plus[4] = t2.x();
    x_plus[5] = t2.y();
    x_plus[6] = t2.z();
    return true;
  }
  bool PlusJacobian(const double*, double* jacobian) const override { return tangentIdentity<7, 6>(jacobian); }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    const Eigen::Quaterniond qy(y[3], y[0], y[1], y[2]), qx(x[3], x[0], x[1], x[2]);
    const Eigen::Quaterniond dq = (qy * qx.conjugate()).normalized();
    const Eigen::AngleAxisd aa(dq);
    const Eigen::Vector3d phi = aa.angle() * aa.axis();
    const Eigen::Vector3d rho = Eigen::Vector3d(y[4], y[5], y[6]) - dq * Eigen::Vector3d(x[4], x[5], x[6]);
    for (int i = 0; i < 3; ++i) {
      y_minus_x[i] = rho[i];
      y_minus_x[3 + i] = phi[i];
    }
    return true;
  }
  bool MinusJacobian(const double*, double* jacobian) const override { return tangentIdentity<6, 7>(jacobian); }

 private:
  // Plus's [I6; 0] and Minus's [I6 0]: the identity between the tangent and the first six parameters.
  template <int Rows, int Cols>
  static bool tangentIdentity(double* jacobian) {
    Eigen::Map<Eigen::Matrix<double, Rows, Cols, Eigen::RowMajor>> J(jacobian);
    J.setZero();
    J.template topLeftCorner<6, 6>().setIdentity();
    return true;
  }
};

}  // namespace beslam::orb::optimize
