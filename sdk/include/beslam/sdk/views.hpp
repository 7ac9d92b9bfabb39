// Zero-copy views between the C ABI's plain structs and cv::Mat / Eigen.
// Mats made from input views point into host memory that is borrowed for one call: read them, never
// keep them. Boxes cross as arrays with an element size; copyBoxes/writeBoxes honour it, so a plugin
// built against an older or newer minor version reads and writes only the fields both sides know.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cstring>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "beslam/formats/geometry.hpp"
#include "beslam/plugin.h"

namespace beslam::sdk {

// Pose conversions and box geometry come from the formats component (beslam/formats/geometry.hpp).
using formats::boxCorners;
using formats::boxPose;
using formats::className;
using formats::motionName;
using formats::newBox;
using formats::objectPose;
using formats::toIsometry;
using formats::toPose;

inline int pixelCvType(int32_t format) {
  switch (format) {
    case BESLAM_PIXEL_GRAY8:
      return CV_8UC1;
    case BESLAM_PIXEL_BGR8:
    case BESLAM_PIXEL_RGB8:
      return CV_8UC3;
    case BESLAM_PIXEL_LABEL16:
      return CV_16UC1;
    default:
      throw std::invalid_argument("unknown pixel format " + std::to_string(format));
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
  return PointMap(cloud.data, 4, cloud.data ? static_cast<Eigen::Index>(cloud.count) : 0, Eigen::OuterStride<>(stride));
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

}  // namespace beslam::sdk
