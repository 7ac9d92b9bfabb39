// Backend: the SLAM or odometry behind the pipeline. Per frame: predictPose(frame) (the pose the motion
// checker uses, empty when unknown), then track(frame, mask, boxes) -> TrackResult (state, T_world_cam,
// keyframe, world_is_metric once the map is in metres). At the end: finish(), then trajectory(which) and
// mapPoints(). addLandmarks() receives a reconstructor's objects; prepare(frame) may do a frame's
// mask-independent work ahead, on another thread. Override predictPose, track and trajectory; the rest is
// optional. Call order: beslam/kinds/backend.h; C glue: detail/backend.hpp.
#pragma once

#include <utility>

#include "beslam/sdk/detail/named_values.hpp"
#include "beslam/sdk/landmark.hpp"
#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

struct TrackResult {
  int32_t state = BESLAM_TRACKING_NOT_INITIALIZED;
  bool is_keyframe = false;
  int64_t keyframe_id = -1;
  int32_t tracked_points = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  std::vector<std::pair<std::string, double>> stage_ms;  // named wall times of this call
  // The world is in metres from this frame on (the backend never goes back to unknown scale).
  bool world_is_metric = false;
  // Named per-frame counts the host sums into summary.json ("features", "features_static", "tracked_static").
  // Events by name: the host also lists the frames where "loop_closures" (with "loop_correction_m", the
  // correction applied, m) or "relocalisations" is above 0.
  std::vector<std::pair<std::string, double>> counters;
  // The frame's features (ABI 1.2), for drawing: pixel, mask label, BESLAM_KEYPOINT_* flags, octave.
  std::vector<beslam_keypoint> keypoints;
  // When is_keyframe (ABI 1.3): the map points the new keyframe observes, for the reconstructor.
  std::vector<KeyframePoint> keyframe_points;
  // ABI 1.7: this call moved the world (a loop correction, a change of scale): a point the world held at
  // p_old is now at world_change_scale * R * p_old + t, [R | t] = *S_new_old, exact about the last tracked
  // camera. Empty when the world stayed.
  std::optional<Eigen::Isometry3d> S_new_old;
  double world_change_scale = 1.0;
};

struct TrajectoryEntry {
  int64_t frame_index = 0;
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

class Backend : public detail::Kind<Backend, BESLAM_KIND_BACKEND> {
 public:
  virtual ~Backend() = default;
  virtual std::optional<Eigen::Isometry3d> predictPose(const Frame& frame) = 0;
  // mask: CV_16UC1 labels, empty without a mask generator; boxes: with track ids and motion states.
  virtual TrackResult track(const Frame& frame, const cv::Mat& mask, const std::vector<beslam_box3d>& boxes) = 0;
  virtual void addLandmarks(const std::vector<Landmark>& /*landmarks*/) {}
  virtual void finish() {}
  // which: BESLAM_TRAJECTORY_FINAL / _ONLINE / _KEYFRAMES.
  virtual std::vector<TrajectoryEntry> trajectory(int32_t which) = 0;
  virtual std::vector<beslam_map_point> mapPoints() { return {}; }
  // ABI 1.4, optional: the frame's work that needs neither mask nor map, done ahead of its track() on the
  // host's producer thread while the other calls run on the main thread (so it must be safe against
  // them); the frame's images are borrowed for this call only. track() must return the same with or
  // without it.
  virtual void prepare(const Frame& /*frame*/) {}

 private:
  friend struct detail::Access;  // the C glue (detail/backend.hpp) keeps here what the host reads
  struct {
    detail::NamedValues<beslam_stage_time> stages;
    detail::NamedValues<beslam_named_value> counters;
    std::vector<beslam_keypoint> keypoints;
    std::vector<beslam_keyframe_point> keyframe_points;
    std::vector<beslam_trajectory_entry> trajectory;
    std::vector<beslam_map_point> points;
  } abi_;
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/backend.hpp"
