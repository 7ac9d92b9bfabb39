// Parallax inside a track's 2D boxes: how far away the car's own surface is, measured by the ego's motion,
// against how far its box says it is.
//
// Per track, corners are found inside its 2D box (shrunk by box_inset on each side, so that less background is
// taken) and followed frame to frame by pyramidal Lucas-Kanade (kept only when the backward flow returns within
// max_flow_error px and the point stays inside the track's box). Once the camera has moved min_baseline metres
// since the corners were found, each is triangulated from the two views with the given metric poses (midpoint of
// the two rays; kept when the rays part by at least min_ray_angle_deg, it reprojects within max_reprojection_px
// in both views and lies in front of both). The measurement is the depth_quantile of the kept points' depths in
// the current camera (the near surface of the car, not the background the box also holds) divided by the depth
// of the lifted 3D box's nearest corner. The same corners are measured every frame from then on, with a growing
// baseline, until they are max_frames old or fewer than min_points; then they are found anew. A track the
// detector misses for up to two frames keeps its corners (followed from the last frame it was seen in).
//
// What the ratio means: a parked car's points are triangulated at their true depth, so the ratio is its lifted
// box's range error (1 / (1 + e)). A car moving along the ego's line of travel at a share k of the ego's speed
// (same direction: k > 0) keeps its points on their epipolar lines but is triangulated at 1 / (1 - k) times its
// depth; one crossing the view leaves its points off their epipolar lines, which the reprojection test drops.
// So a ratio near 1 rejects every motion except a slow one along the line of travel (the epipolar ambiguity
// no monocular camera resolves without a better range than the box's). Plain C++ over OpenCV and the ABI's box.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <map>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "beslam/data.h"

namespace beslam::motion {

struct ParallaxParams {
  double min_baseline = 2.0;         // m the camera moves between the two views of a measurement
  double min_ray_angle_deg = 1.0;    // a corner's two rays must part by this much (its depth to a few per cent)
  int max_frames = 10;               // frames a set of corners is followed before it is found anew
  int corners = 60;                  // corners sought in a box
  double box_inset = 0.15;           // share of the box's width and height left out on each side
  double max_flow_error = 1.0;       // px: forward-backward Lucas-Kanade disagreement
  double max_reprojection_px = 1.5;  // px, in both views
  double depth_quantile = 0.3;       // of the kept points' depths: the car's near surface
  int min_points = 6;                // kept points a measurement needs
  int min_box_px = 24;               // boxes narrower or lower than this are not followed

  // Empty when valid, else the first violated constraint.
  std::string validate() const;
};

struct ParallaxMeasurement {
  int32_t track_id = -1;
  double depth_ratio = 0;  // triangulated near-surface depth / lifted box's nearest-corner depth
  int points = 0;          // points behind it
};

class ParallaxCheck {
 public:
  // K: the rectified pinhole camera the images come from.
  ParallaxCheck(const ParallaxParams& params, double fx, double fy, double cx, double cy);

  // One frame: gray image (CV_8UC1), the camera's metric pose, and the boxes with the track ids the tracker
  // gave them. Boxes without a 2D box, with track id -1 or flagged uncertain are not followed. Returns the
  // measurements made this frame (at most one a track). Without a pose every set of corners is dropped.
  std::vector<ParallaxMeasurement> update(const cv::Mat& gray, const std::optional<Eigen::Isometry3d>& T_world_cam,
                                          const std::vector<beslam_box3d>& boxes);

  void reset();
  const ParallaxParams& params() const { return params_; }

 private:
  struct PointSet {
    Eigen::Isometry3d T_world_cam0;   // pose of the view the corners were found in
    std::vector<cv::Point2f> first;   // where they were found
    std::vector<cv::Point2f> latest;  // where they are now
    int frames = 0;
    int64_t latest_frame = 0;  // the call (frame_) `latest` was measured in
  };
  static constexpr int kKeptPyramids = 3;  // a track missed by the detector for up to two frames keeps its corners
  void seed(PointSet& set, const cv::Mat& gray, const Eigen::Isometry3d& T_world_cam, const beslam_box3d& box) const;
  std::optional<ParallaxMeasurement> measure(const PointSet& set, const Eigen::Isometry3d& T_world_cam,
                                             const beslam_box3d& box) const;

  ParallaxParams params_;
  double fx_, fy_, cx_, cy_;
  int64_t frame_ = 0;                                              // calls with an image and a pose
  std::deque<std::pair<int64_t, std::vector<cv::Mat>>> pyramids_;  // the last frames' image pyramids
  std::map<int32_t, PointSet> sets_;
};

// Depth (camera z) of the nearest of a 3D box's eight corners (camera frame, KITTI yaw about y).
double nearestCornerDepth(const beslam_box3d& box);

}  // namespace beslam::motion
