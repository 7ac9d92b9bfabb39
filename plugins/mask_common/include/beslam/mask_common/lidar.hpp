// LiDAR side of Algorithm 1: the scan into the rectified camera frame (the KITTI chain P * R0_rect *
// Tr_velo_to_cam, composed by the host into T_cam_lidar and the intrinsics), points in front of the
// camera and inside the image kept, a bird's-eye view (camera x right / z forward plane), each box
// matched to the points in and around it, the box fine-tuned to those points in the BEV with its
// vertical extent (camera y, the paper's "z") kept, and per-object masks from the projected points.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "beslam/data.h"
#include "beslam/mask_common/box_projection.hpp"

namespace beslam::mask {

// Points of one scan in the camera frame that are in front of the camera (z >= near, range <=
// max_range) and project inside the image.
struct CameraPoints {
  std::vector<Eigen::Vector3f> p;  // camera frame
  std::vector<cv::Point2f> uv;     // pixels
  static constexpr int kBinPx = 16;
  std::vector<std::vector<int>> column_bins;  // indices of the points in each 16-px image column band
  size_t size() const { return p.size(); }
};

// xyzi: `count` points, `stride_floats` floats apart (>= 4), x y z intensity in the LiDAR frame.
CameraPoints lidarToCamera(const float* xyzi, size_t count, size_t stride_floats, const Eigen::Isometry3d& T_cam_lidar,
                           const Intrinsics& K, double near = 0.5, double max_range = 120.0);

struct BevRefineParams {
  double search_margin = 1.0;     // m: points this far around the box (BEV) are candidates
  double ground_clearance = 0.3;  // m: points within this of the box bottom are ground (road, kerb and
                                  // pavement) and ignored
  double cluster_gap = 0.45;      // m: BEV connectivity of one object's points
  double yaw_range_deg = 15.0;    // yaw searched around the input's
  int min_points = 15;            // fewer matched points: keep the input box
  double yaw_prior_weight = 0.2;  // m per rad^2 added to the fit cost for leaving the input yaw
  int min_outline_for_yaw = 20;   // fewer outline returns (nearest per 0.2 deg azimuth): yaw kept
  double max_truncation = 0.5;    // boxes with more of their image outside the frame keep their pose
  Intrinsics intrinsics;          // for the truncation test (width 0: no test)
};

struct BevRefineResult {
  beslam_box3d box{};  // refined (or the input when not refined)
  bool refined = false;
  int points = 0;   // points matched to the object
  double cost = 0;  // mean L-shape distance (m) of the fit
};

// Fraction of the box's (unclipped) image area outside the image, 0..1 (1 when behind the camera).
double truncatedFraction(const beslam_box3d& box, const Intrinsics& K);

// Indices of the points inside the box grown by `margin` in the BEV, between the box top and its bottom
// minus `ground_clearance` vertically.
// With K (and points from lidarToCamera) only the column bands the grown box projects to are scanned.
std::vector<int> pointsNearBox(const beslam_box3d& box, const CameraPoints& points, double margin,
                               double ground_clearance, const Intrinsics* K = nullptr);

// Fine-tunes centre (x, z) and yaw of the box to the object's points in the BEV; size, centre y (the
// vertical extent) kept. The box's own points: the BEV cluster (cluster_gap connectivity) of the
// candidates that overlaps the input box most. The fit aligns the box's sensor-facing sides with the
// points (fixed-size L-shape fit), penalising points left outside the box.
BevRefineResult refineBoxBev(const beslam_box3d& box, const CameraPoints& points, const BevRefineParams& params);

struct PointMaskParams {
  double ground_clearance = 0.15;  // m: the object's points start this far above its box bottom
  int min_points = 40;             // fewer projected object points: no point mask
  double min_coverage = 0.35;      // splatted points must cover this fraction of the box polygon
  int splat_half_width = 2;        // px: each point covers (2*hw+1) x (2*hh+1)
  int splat_half_height = 4;
  int close_px = 5;  // morphological closing of the splats
};

// A per-object mask (CV_8UC1 of roi's size, 255 inside) from the object's projected points, clipped to
// `polygon_mask` (same size): splats closed and hole-filled. Empty Mat when the points are too sparse.
cv::Mat pointMask(const CameraPoints& points, const std::vector<int>& indices, const cv::Rect& roi,
                  const cv::Mat& polygon_mask, const PointMaskParams& params);

// BEV distance between box centres (m) and absolute yaw difference (rad, modulo pi: a box is symmetric).
double bevCentreError(const beslam_box3d& a, const beslam_box3d& b);
double yawError(const beslam_box3d& a, const beslam_box3d& b);

}  // namespace beslam::mask
