// The mask generator core both plugins share: boxes (+ optional LiDAR scan) to a label mask.
//   mask_box:   polygon = projected box (+ margin); contour refinement optional.
//   mask_lidar: box fine-tuned to the scan in the BEV first; per-object point mask where the projected
//               points are dense enough; contour refinement optional (guided by the point mask).
// Each object is computed on its own crop and painted far to near, so nearer objects win overlaps.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "beslam/data.h"
#include "beslam/mask_common/box_projection.hpp"
#include "beslam/mask_common/contour.hpp"
#include "beslam/mask_common/lidar.hpp"

namespace beslam::mask {

struct MaskOptions {
  double margin_px = 2.0;  // added around the projected polygon
  double near = 0.3;       // near plane (m)
  UnknownPolicy unknown = UnknownPolicy::Dynamic;
  bool contour = false;  // edge contour refinement
  ContourParams contour_params;
  bool use_lidar = false;    // mask_lidar
  bool refine_boxes = true;  // BEV fine-tuning (needs use_lidar)
  bool point_masks = true;   // per-object masks from projected points (needs use_lidar)
  double max_range = 80.0;   // LiDAR points beyond this are ignored
  BevRefineParams bev;
  PointMaskParams points;
};

struct ObjectMask {
  beslam_box3d input{};  // as received
  beslam_box3d box{};    // as used (refined with LiDAR)
  uint16_t label = 0;
  cv::Rect roi;               // crop in the image
  cv::Mat mask;               // CV_8UC1 of roi's size (255 inside); empty when not visible
  bool refined = false;       // box fine-tuned to LiDAR
  bool from_points = false;   // point mask used
  bool from_contour = false;  // contour refinement succeeded
  int lidar_points = 0;
};

class MaskBuilder {
 public:
  // T_cam_lidar needed when options.use_lidar (throws std::invalid_argument otherwise).
  MaskBuilder(const Intrinsics& K, const std::optional<Eigen::Isometry3d>& T_cam_lidar, const MaskOptions& options);

  // Per-object masks for the boxes that get a label (see labelFor), in input order.
  std::vector<ObjectMask> objects(const cv::Mat& gray, const beslam_point_cloud_view& lidar,
                                  const std::vector<beslam_box3d>& boxes) const;

  // Writes labels into mask (CV_16UC1, image size), far objects first so near ones overwrite.
  void paint(const std::vector<ObjectMask>& objects, cv::Mat& mask) const;

  void generate(const cv::Mat& gray, const beslam_point_cloud_view& lidar, const std::vector<beslam_box3d>& boxes,
                cv::Mat& mask) const {
    paint(objects(gray, lidar, boxes), mask);
  }

  const MaskOptions& options() const { return options_; }

 private:
  Intrinsics K_;
  std::optional<Eigen::Isometry3d> T_cam_lidar_;
  MaskOptions options_;
};

}  // namespace beslam::mask
