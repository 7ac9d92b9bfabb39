// Object landmarks in bundle adjustment (docs/object-ba.md).
//
// Object node: 4 doubles [yaw, tx, ty, tz]: T_world_object = [R0 * Rz(yaw) | t], R0 the landmark's
// rotation when the BA call starts (yaw starts at 0). 4-DoF on purpose: the reconstructor fits cars
// standing on the road (their up axis is right), and a box detection measures yaw only, so roll and
// pitch of the object would be unobserved or absorb the camera's tilt errors.
//
// Camera-object factor (ObjectBoxCost, 4 residuals): a keyframe's box of the car, as T_cam_object (box
// centre, yaw), against T_cam_world * T_world_object: the centre difference in the camera frame over
// sigma_pos = box_sigma + box_sigma_per_m * range, and the heading difference (the object's x axis in
// the camera's x-z plane, wrapped to (-90, 90] degrees: detectors confuse front and back) over sigma_yaw.
// Map-point-on-surface factor (SurfacePointCost, 3 residuals): a map point on the car, in the object
// frame, minus its nearest surface sample (associated anew at each BA call), projected on the sample's
// surface normal (point-to-plane: the point may slide along the surface, so the samples' spacing does not
// hold the object in place), over surface_sigma; point-to-point where the sample has no normal.
// Both scaled by sqrt(weight * confidence), a surface factor's weight divided by its car's point count
// (object_ba.cpp: the car's points are one observation); the caller adds a Huber loss. Camera poses use the left
// tangent of optimize/se3.hpp (Jacobian in the first six of seven columns); derivatives come from Jets.
#pragma once

#include <ceres/jet.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Geometry>
#include <cmath>

#include "beslam_orb/options.hpp"
#include "beslam_orb/types.hpp"

namespace beslam::orb::objects {

// ObjectBox axes (x heading, y down, z across) -> landmark body axes (x forward, y left, z up), data.h.
inline Eigen::Matrix3d boxToBody() {
  Eigen::Matrix3d M;  // columns: body x, y, z in box axes
  M << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  return M;
}
inline Eigen::Isometry3d objectPoseOfBox(const ObjectBox& box) {
  Eigen::Isometry3d T_cam_object = box.T_cam_box;
  T_cam_object.linear() = box.T_cam_box.linear() * boxToBody();
  return T_cam_object;
}

// Heading of the object's x axis in the camera's x-z plane (KITTI rotation_y convention).
template <typename T>
T headingInCamera(const Eigen::Matrix<T, 3, 1>& x_axis_cam) {
  using std::atan2;
  return atan2(-x_axis_cam.z(), x_axis_cam.x());
}

inline Eigen::Isometry3d nodeToPose(const Eigen::Matrix3d& R0, const double* node) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R0 * Eigen::AngleAxisd(node[0], Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(node[1], node[2], node[3]);
  return T;
}

namespace detail {
template <typename T>
Eigen::Matrix<T, 3, 3> nodeRotation(const Eigen::Matrix3d& R0, const T* node) {
  using std::cos;
  using std::sin;
  Eigen::Matrix<T, 3, 3> Rz = Eigen::Matrix<T, 3, 3>::Identity();
  Rz(0, 0) = cos(node[0]);
  Rz(0, 1) = -sin(node[0]);
  Rz(1, 0) = sin(node[0]);
  Rz(1, 1) = cos(node[0]);
  return R0.cast<T>() * Rz;
}
inline double wrapHalfTurn(double a) { return a - M_PI * std::round(a / M_PI); }
}  // namespace detail

class ObjectBoxCost : public ceres::SizedCostFunction<4, 7, 4> {
 public:
  // T_cam_object: the box as the landmark's body frame (objectPoseOfBox); scale = sqrt(weight * confidence).
  ObjectBoxCost(const Eigen::Isometry3d& T_cam_object, const Eigen::Matrix3d& R0, double sigma_pos, double sigma_yaw,
                double scale)
      : t_meas_(T_cam_object.translation()),
        yaw_meas_(headingInCamera<double>(T_cam_object.linear().col(0))),
        R0_(R0),
        w_pos_(scale / sigma_pos),
        w_yaw_(scale / sigma_yaw) {}

  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    using J = ceres::Jet<double, 10>;
    const double* pose = params[0];
    const Eigen::Matrix3d R_cw = Eigen::Quaterniond(pose[3], pose[0], pose[1], pose[2]).toRotationMatrix();
    const Eigen::Vector3d t_cw(pose[4], pose[5], pose[6]);
    J d[6], node[4], r[4];
    for (int i = 0; i < 6; ++i) d[i] = J(0.0, i);
    for (int i = 0; i < 4; ++i) node[i] = J(params[1][i], 6 + i);
    // Left perturbation to first order (exact first derivatives at delta = 0): R = (I + [phi]x) R_cw,
    // t = t_cw + phi x t_cw + rho.
    const Eigen::Matrix<J, 3, 1> rho(d[0], d[1], d[2]), phi(d[3], d[4], d[5]);
    Eigen::Matrix<J, 3, 3> skew;
    skew << J(0.0), -phi.z(), phi.y(), phi.z(), J(0.0), -phi.x(), -phi.y(), phi.x(), J(0.0);
    const Eigen::Matrix<J, 3, 3> R = (Eigen::Matrix<J, 3, 3>::Identity() + skew) * R_cw.cast<J>();
    const Eigen::Matrix<J, 3, 1> t = t_cw.cast<J>() + phi.cross(t_cw.cast<J>()) + rho;
    const Eigen::Matrix<J, 3, 3> R_co = R * detail::nodeRotation(R0_, node);
    const Eigen::Matrix<J, 3, 1> t_co = R * Eigen::Matrix<J, 3, 1>(node[1], node[2], node[3]) + t;
    for (int i = 0; i < 3; ++i) r[i] = (t_co[i] - J(t_meas_[i])) * w_pos_;
    const J yaw = headingInCamera<J>(R_co.col(0));
    const double wrap = yaw_meas_ + detail::wrapHalfTurn(yaw.a - yaw_meas_) - yaw.a;  // a constant shift
    r[3] = (yaw - J(yaw_meas_) + J(wrap)) * w_yaw_;
    for (int i = 0; i < 4; ++i) residuals[i] = r[i].a;
    if (jacobians && jacobians[0])
      for (int i = 0; i < 4; ++i) {
        for (int k = 0; k < 6; ++k) jacobians[0][7 * i + k] = r[i].v[k];
        jacobians[0][7 * i + 6] = 0;
      }
    if (jacobians && jacobians[1])
      for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 4; ++k) jacobians[1][4 * i + k] = r[i].v[6 + k];
    return true;
  }

 private:
  Eigen::Vector3d t_meas_;
  double yaw_meas_;
  Eigen::Matrix3d R0_;
  double w_pos_, w_yaw_;
};

class SurfacePointCost : public ceres::SizedCostFunction<3, 3, 4> {
 public:
  // q_object, n_object: the associated surface sample and its unit normal (zero: none), object frame;
  // scale = sqrt(weight * confidence).
  SurfacePointCost(const Eigen::Vector3d& q_object, const Eigen::Vector3d& n_object, const Eigen::Matrix3d& R0,
                   double sigma, double scale)
      : q_(q_object),
        P_(n_object.squaredNorm() > 0 ? Eigen::Matrix3d(n_object * n_object.transpose()) : Eigen::Matrix3d::Identity()),
        R0_(R0),
        w_(scale / sigma) {}

  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    using J = ceres::Jet<double, 7>;
    J p[3], node[4];
    for (int i = 0; i < 3; ++i) p[i] = J(params[0][i], i);
    for (int i = 0; i < 4; ++i) node[i] = J(params[1][i], 3 + i);
    const Eigen::Matrix<J, 3, 1> p_obj =
        detail::nodeRotation(R0_, node).transpose() *
        (Eigen::Matrix<J, 3, 1>(p[0], p[1], p[2]) - Eigen::Matrix<J, 3, 1>(node[1], node[2], node[3]));
    const Eigen::Matrix<J, 3, 1> d = P_.cast<J>() * (p_obj - q_.cast<J>());
    for (int i = 0; i < 3; ++i) {
      const J r = d[i] * w_;
      residuals[i] = r.a;
      if (jacobians && jacobians[0])
        for (int k = 0; k < 3; ++k) jacobians[0][3 * i + k] = r.v[k];
      if (jacobians && jacobians[1])
        for (int k = 0; k < 4; ++k) jacobians[1][4 * i + k] = r.v[3 + k];
    }
    return true;
  }

 private:
  Eigen::Vector3d q_;
  Eigen::Matrix3d P_;  // projection on the normal, or identity
  Eigen::Matrix3d R0_;
  double w_;
};

}  // namespace beslam::orb::objects
