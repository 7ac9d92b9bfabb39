// Pose and box geometry over the ABI's plain structs (beslam/data.h), Eigen only.
// Poses: beslam_pose is the top 3x4 of a rigid transform, row-major; T_a_b maps frame b into a.
// Boxes: camera frame x right, y down, z forward; center_cam is the geometric centre, size is length,
// width, height, yaw is KITTI's rotation_y about the camera y axis. KITTI labels give the bottom centre.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

#include "beslam/data.h"

namespace beslam::formats {

inline Eigen::Isometry3d toIsometry(const beslam_pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = pose.m[r * 4 + c];
  return T;
}

inline beslam_pose toPose(const Eigen::Isometry3d& T) {
  beslam_pose pose{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) pose.m[r * 4 + c] = T.matrix()(r, c);
  return pose;
}

// A box with the ABI's neutral defaults: no track, motion unknown, no optional fields.
inline beslam_box3d newBox() {
  beslam_box3d box{};
  box.track_id = -1;
  box.motion_state = BESLAM_MOTION_UNKNOWN;
  return box;
}

// KITTI bottom-centre label geometry (h w l, x y z, ry) to an ABI box (centre y = y_bottom - h / 2),
// score 1, no track, motion unknown.
inline beslam_box3d boxFromKitti(int32_t class_id, double h, double w, double l, double x, double y, double z,
                                 double ry) {
  beslam_box3d b = newBox();
  b.class_id = class_id;
  b.center_cam[0] = x;
  b.center_cam[1] = y - h / 2;  // KITTI gives the bottom centre (y points down)
  b.center_cam[2] = z;
  b.size[0] = l;
  b.size[1] = w;
  b.size[2] = h;
  b.yaw = ry;
  b.score = 1.0f;
  return b;
}

// Pose of a box in the camera frame: rotation yaw about the camera y axis, origin at the box centre.
// The box frame has x along the heading (length), y down (height), z across (width), KITTI style.
inline Eigen::Isometry3d boxPose(const beslam_box3d& box) {
  Eigen::Isometry3d T_cam_box = Eigen::Isometry3d::Identity();
  T_cam_box.linear() = Eigen::AngleAxisd(box.yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_cam_box.translation() = Eigen::Vector3d(box.center_cam[0], box.center_cam[1], box.center_cam[2]);
  return T_cam_box;
}

// Pose of a box as an object landmark's body frame (x forward, y left, z up; data.h): T_cam_object.
inline Eigen::Isometry3d objectPose(const beslam_box3d& box) {
  Eigen::Matrix3d M;  // columns: body x, y, z in box axes (x heading, y down, z across)
  M << 1, 0, 0,       //
      0, 0, -1,       //
      0, 1, 0;
  Eigen::Isometry3d T_cam_object = boxPose(box);
  T_cam_object.linear() = T_cam_object.linear() * M;
  return T_cam_object;
}

// The eight corners of a box in the camera frame (columns), bottom face first.
inline Eigen::Matrix<double, 3, 8> boxCorners(const beslam_box3d& box) {
  const double l = box.size[0] / 2, w = box.size[1] / 2, h = box.size[2] / 2;
  Eigen::Matrix<double, 3, 8> p_box;
  p_box << l, l, -l, -l, l, l, -l, -l,  //
      h, h, h, h, -h, -h, -h, -h,       // y down: +h is the bottom
      w, -w, -w, w, w, -w, -w, w;
  return boxPose(box) * p_box;
}

// A dataset's class name and the ABI class it maps to; classByName() looks a name up in such a table.
struct NamedClass {
  const char* name;
  int32_t class_id;
};
template <std::size_t N>
bool classByName(const std::string& name, const NamedClass (&table)[N], int32_t& class_id) {
  for (const NamedClass& c : table)
    if (name == c.name) {
      class_id = c.class_id;
      return true;
    }
  return false;
}

// KITTI label types: Car Van Truck Pedestrian Person_sitting (Person) Cyclist, Tram and Misc
// (-> BESLAM_CLASS_UNKNOWN). False for a name KITTI does not know.
inline bool kittiClass(const std::string& name, int32_t& class_id) {
  static const NamedClass kKitti[] = {{"Car", BESLAM_CLASS_CAR},
                                      {"Van", BESLAM_CLASS_VAN},
                                      {"Truck", BESLAM_CLASS_TRUCK},
                                      {"Pedestrian", BESLAM_CLASS_PEDESTRIAN},
                                      {"Person_sitting", BESLAM_CLASS_PEDESTRIAN},
                                      {"Person", BESLAM_CLASS_PEDESTRIAN},
                                      {"Cyclist", BESLAM_CLASS_CYCLIST},
                                      {"Tram", BESLAM_CLASS_UNKNOWN},
                                      {"Misc", BESLAM_CLASS_UNKNOWN}};
  return classByName(name, kKitti, class_id);
}

// The ABI class's KITTI-style name ("Misc" for unknown ids) and a motion state's name.
inline const char* className(int32_t class_id) {
  static const std::pair<int32_t, const char*> kNames[] = {{BESLAM_CLASS_CAR, "Car"},
                                                           {BESLAM_CLASS_PEDESTRIAN, "Pedestrian"},
                                                           {BESLAM_CLASS_CYCLIST, "Cyclist"},
                                                           {BESLAM_CLASS_TRUCK, "Truck"},
                                                           {BESLAM_CLASS_VAN, "Van"}};
  for (const auto& [id, name] : kNames)
    if (id == class_id) return name;
  return "Misc";
}

inline const char* motionName(int32_t state) {
  return state == BESLAM_MOTION_STATIC ? "static" : state == BESLAM_MOTION_DYNAMIC ? "dynamic" : "unknown";
}

}  // namespace beslam::formats
