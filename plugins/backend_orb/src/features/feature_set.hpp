// The features of one image: keypoints (level-0 pixels, octave = pyramid level), rBRIEF descriptors,
// per-keypoint label/colour, and a 64 x 48 grid for constant-time "keypoints near (u, v)" queries.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "beslam_orb/types.hpp"

namespace beslam::orb {

class FeatureGrid {
 public:
  static constexpr int kCols = 64, kRows = 48;
  FeatureGrid() = default;
  FeatureGrid(const std::vector<cv::KeyPoint>& keypoints, int width, int height);
  // Indices of keypoints within radius r (square window) of (u, v), with min_level <= octave <= max_level
  // (a negative bound means unbounded).
  std::vector<int> query(const std::vector<cv::KeyPoint>& keypoints, float u, float v, float r, int min_level = -1,
                         int max_level = -1) const;
  // The grid cells that intersect the window [x0,x1] x [y0,y1], row by row: columns c0..c1 of rows r0..r1
  // (none when either range is empty or the grid is, or a bound is NaN); a cell's keypoint indices,
  // increasing, are [cellBegin, cellEnd). Inline: the epipolar search of triangulation asks it for every
  // grid row a keypoint's line crosses.
  bool cellRange(float x0, float y0, float x1, float y1, int& c0, int& c1, int& r0, int& r1) const {
    if (start_.empty() || std::isnan(x0) || std::isnan(y0) || std::isnan(x1) || std::isnan(y1)) return false;
    c0 = std::max(0, cellFloor(x0 * inv_cell_w_));
    c1 = std::min(kCols - 1, cellFloor(x1 * inv_cell_w_));
    r0 = std::max(0, cellFloor(y0 * inv_cell_h_));
    r1 = std::min(kRows - 1, cellFloor(y1 * inv_cell_h_));
    return c0 <= c1 && r0 <= r1;
  }
  const int* cellBegin(int cell) const { return start_.empty() ? nullptr : index_.data() + start_[cell]; }
  const int* cellEnd(int cell) const { return start_.empty() ? nullptr : index_.data() + start_[cell + 1]; }

 private:
  // floor(v) as an int for a position v in cells, by truncation and one down for negative fractions
  // (shorter than the rounding sequence std::floor compiles to without SSE4.1), v first clamped to
  // [-1, 1e9]: left of the grid is column (row) -1, far right of it beyond the last, as unclamped.
  static int cellFloor(float v) {
    if (!(v > -1.f)) return -1;
    if (v >= 1e9f) return 1000000000;
    const int i = static_cast<int>(v);
    return static_cast<float>(i) > v ? i - 1 : i;
  }
  float inv_cell_w_ = 0, inv_cell_h_ = 0;
  std::vector<int> start_;  // kCols*kRows+1 offsets into index_
  std::vector<int> index_;
};

struct FeatureSet {
  int width = 0, height = 0;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;             // N x 32, CV_8U
  std::vector<uint16_t> labels;    // mask value under each keypoint (0 without a mask)
  std::vector<cv::Vec3b> colours;  // BGR (grey repeated for grey input)
  // Metres from the camera to where the keypoint's ray enters the metric 3D box of the static object it
  // lies on (OrbSlam::ObjectBox), 0 where there is none. Empty when the frame had no boxes.
  std::vector<float> object_range;
  // Metres from the camera to the surface a LiDAR scan of the frame saw under the keypoint
  // (scale/lidar_range.hpp), 0 where the scan says nothing clear. Empty when the frame had no scan.
  std::vector<float> lidar_range;
  // The frame's boxes of parked (static) tracked cars, kept with the keyframe for local BA: the parked cars'
  // anchors (metric scale) and the object landmarks' camera-object factors (objects/object_factors.hpp).
  // Filled only when one of them is on.
  std::vector<ObjectBox> object_boxes;
  FeatureGrid grid;

  size_t size() const { return keypoints.size(); }
  const uint8_t* descriptor(size_t i) const { return descriptors.ptr<uint8_t>(static_cast<int>(i)); }
  bool onStaticObject(size_t i) const { return labels[i] >= 1000; }
  float objectRange(size_t i) const { return i < object_range.size() ? object_range[i] : 0.0f; }
  float lidarRange(size_t i) const { return i < lidar_range.size() ? lidar_range[i] : 0.0f; }
  int32_t objectId(size_t i) const { return labels[i] >= 1000 ? static_cast<int32_t>(labels[i]) - 1000 : -1; }
  void buildGrid() { grid = FeatureGrid(keypoints, width, height); }
  std::vector<int> query(float u, float v, float r, int min_level = -1, int max_level = -1) const {
    return grid.query(keypoints, u, v, r, min_level, max_level);
  }
};

}  // namespace beslam::orb
