// Zero-copy views between the C ABI's plain structs and cv::Mat / Eigen, and pose conversions.
// Mats made from input views point into host memory that is borrowed for one call: read them, never
// keep them. Boxes cross as arrays with an element size; copyBoxes/writeBoxes honour it, so a plugin
// built against an older or newer minor version reads and writes only the fields both sides know.
#pragma once

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "beslam/plugin.h"

namespace beslam::sdk {

inline int pixelCvType(int32_t format) {
  switch (format) {
    case BESLAM_PIXEL_GRAY8: return CV_8UC1;
    case BESLAM_PIXEL_BGR8:
    case BESLAM_PIXEL_RGB8: return CV_8UC3;
    case BESLAM_PIXEL_LABEL16: return CV_16UC1;
    default: throw std::invalid_argument("unknown pixel format " + std::to_string(format));
  }
}

// A cv::Mat header over an image view (no copy); an empty Mat when the view has no data.
inline cv::Mat toMat(const beslam_image_view& view) {
  if (view.data == nullptr) return {};
  return cv::Mat(view.height, view.width, pixelCvType(view.format), const_cast<uint8_t*>(view.data),
                 static_cast<size_t>(view.stride_bytes));
}

// A writable CV_16UC1 header over a host-owned mask buffer.
inline cv::Mat toMat(beslam_mask_buffer& mask) {
  return cv::Mat(mask.height, mask.width, CV_16UC1, mask.data, static_cast<size_t>(mask.stride_bytes));
}

// An image view over a cv::Mat the caller keeps alive for the duration of the call.
inline beslam_image_view toView(const cv::Mat& mat, int32_t format) {
  beslam_image_view view{};
  if (mat.empty()) return view;
  view.data = mat.data;
  view.width = mat.cols;
  view.height = mat.rows;
  view.stride_bytes = static_cast<int32_t>(mat.step[0]);
  view.format = format;
  return view;
}

// LiDAR points as a 4xN float matrix (x y z intensity per column) over the host's buffer, honouring stride.
using PointMap = Eigen::Map<const Eigen::Matrix<float, 4, Eigen::Dynamic>, 0, Eigen::OuterStride<>>;
inline PointMap toEigen(const beslam_point_cloud_view& cloud) {
  const Eigen::Index stride = cloud.stride_bytes >= 16 ? cloud.stride_bytes / 4 : 4;
  return PointMap(cloud.data, 4, cloud.data ? static_cast<Eigen::Index>(cloud.count) : 0,
                  Eigen::OuterStride<>(stride));
}

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

// Copies an element-sized C array into whole structs (unknown trailing fields zero-filled).
template <class T>
std::vector<T> copyArray(const T* items, uint64_t count, uint32_t element_size) {
  std::vector<T> out(count);
  if (items == nullptr || count == 0) return out;
  const size_t n = std::min<size_t>(element_size, sizeof(T));
  const char* base = reinterpret_cast<const char*>(items);
  for (uint64_t i = 0; i < count; ++i) {
    std::memset(&out[i], 0, sizeof(T));
    std::memcpy(&out[i], base + i * element_size, n);
  }
  return out;
}

inline std::vector<beslam_box3d> copyBoxes(const beslam_box_list* list) {
  if (list == nullptr) return {};
  return copyArray(list->boxes, list->count, list->element_size);
}

// Writes boxes back into an element-sized host array of the same count (the fields both sides know).
inline void writeBoxes(const std::vector<beslam_box3d>& boxes, beslam_box_array& array) {
  const size_t n = std::min<size_t>(array.element_size, sizeof(beslam_box3d));
  char* base = reinterpret_cast<char*>(array.boxes);
  for (uint32_t i = 0; i < array.count && i < boxes.size(); ++i)
    std::memcpy(base + static_cast<size_t>(i) * array.element_size, &boxes[i], n);
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
  M << 1, 0, 0,  //
      0, 0, -1,  //
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

inline const char* className(int32_t class_id) {
  switch (class_id) {
    case BESLAM_CLASS_CAR: return "Car";
    case BESLAM_CLASS_PEDESTRIAN: return "Pedestrian";
    case BESLAM_CLASS_CYCLIST: return "Cyclist";
    case BESLAM_CLASS_TRUCK: return "Truck";
    case BESLAM_CLASS_VAN: return "Van";
    default: return "Misc";
  }
}

inline const char* motionName(int32_t state) {
  switch (state) {
    case BESLAM_MOTION_STATIC: return "static";
    case BESLAM_MOTION_DYNAMIC: return "dynamic";
    default: return "unknown";
  }
}

}  // namespace beslam::sdk
