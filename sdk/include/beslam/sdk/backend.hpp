// Backend base class: the SLAM or odometry behind the pipeline (see beslam/kinds/backend.h for the call
// order). Override predictPose, track and trajectory; addLandmarks, finish and mapPoints are optional.
#pragma once

#include <utility>

#include "beslam/sdk/landmark.hpp"

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
  std::vector<std::pair<std::string, double>> counters;
  // The frame's features (ABI 1.2), for drawing: pixel, mask label, BESLAM_KEYPOINT_* flags, octave.
  std::vector<beslam_keypoint> keypoints;
};

struct TrajectoryEntry {
  int64_t frame_index = 0;
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

class Backend {
 public:
  static constexpr int32_t kKind = BESLAM_KIND_BACKEND;
  virtual ~Backend() = default;
  virtual std::optional<Eigen::Isometry3d> predictPose(const Frame& frame) = 0;
  // mask: CV_16UC1 labels, empty without a mask generator; boxes: with track ids and motion states.
  virtual TrackResult track(const Frame& frame, const cv::Mat& mask, const std::vector<beslam_box3d>& boxes) = 0;
  virtual void addLandmarks(const std::vector<Landmark>& /*landmarks*/) {}
  virtual void finish() {}
  // which: BESLAM_TRAJECTORY_FINAL / _ONLINE / _KEYFRAMES.
  virtual std::vector<TrajectoryEntry> trajectory(int32_t which) = 0;
  virtual std::vector<beslam_map_point> mapPoints() { return {}; }

  template <class Impl>
  static const void* functionTable() {
    static const beslam_backend_v1 table = {
        sizeof(beslam_backend_v1),
        0,
        // predict_pose
        [](void* instance, const beslam_frame* frame, beslam_pose* T_world_cam, int32_t* valid) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr || T_world_cam == nullptr || valid == nullptr)
              throw std::invalid_argument("predict_pose: null argument");
            const auto pose = static_cast<Backend&>(*self->impl).predictPose(toFrame(frame));
            *valid = pose ? 1 : 0;
            if (pose) *T_world_cam = toPose(*pose);
          });
        },
        // track
        [](void* instance, const beslam_frame* frame, const beslam_image_view* mask, const beslam_box_list* boxes,
           beslam_track_result* result) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr || result == nullptr) throw std::invalid_argument("track: null argument");
            Backend& b = *self->impl;
            const TrackResult r = b.track(toFrame(frame), mask ? toMat(*mask) : cv::Mat(), copyBoxes(boxes));
            b.abi_stage_names_.clear();
            b.abi_stages_.clear();
            for (const auto& [name, ms] : r.stage_ms) b.abi_stage_names_.push_back(name);
            for (size_t i = 0; i < r.stage_ms.size(); ++i)
              b.abi_stages_.push_back({b.abi_stage_names_[i].c_str(), r.stage_ms[i].second});
            beslam_track_result c{};
            c.struct_size = sizeof(c);
            c.state = r.state;
            c.is_keyframe = r.is_keyframe ? 1 : 0;
            c.tracked_points = r.tracked_points;
            c.keyframe_id = r.keyframe_id;
            c.T_world_cam = toPose(r.T_world_cam);
            c.stage_times = b.abi_stages_.empty() ? nullptr : b.abi_stages_.data();
            c.stage_count = static_cast<uint32_t>(b.abi_stages_.size());
            c.world_scale = r.world_is_metric ? BESLAM_WORLD_SCALE_METRIC : BESLAM_WORLD_SCALE_UNKNOWN;
            b.abi_counter_names_.clear();
            b.abi_counters_.clear();
            for (const auto& [name, value] : r.counters) b.abi_counter_names_.push_back(name);
            for (size_t i = 0; i < r.counters.size(); ++i)
              b.abi_counters_.push_back({b.abi_counter_names_[i].c_str(), r.counters[i].second});
            c.counters = b.abi_counters_.empty() ? nullptr : b.abi_counters_.data();
            c.counter_count = static_cast<uint32_t>(b.abi_counters_.size());
            b.abi_keypoints_ = r.keypoints;
            c.keypoints = b.abi_keypoints_.empty() ? nullptr : b.abi_keypoints_.data();
            c.keypoint_count = static_cast<uint32_t>(b.abi_keypoints_.size());
            c.keypoint_size = sizeof(beslam_keypoint);
            std::memcpy(result, &c, std::min<size_t>(result->struct_size ? result->struct_size : sizeof(c), sizeof(c)));
          });
        },
        // add_landmarks
        [](void* instance, const beslam_landmark_list* landmarks) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr) throw std::invalid_argument("add_landmarks: null instance");
            static_cast<Backend&>(*self->impl).addLandmarks(fromC(landmarks));
          });
        },
        // finish
        [](void* instance) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr) throw std::invalid_argument("finish: null instance");
            static_cast<Backend&>(*self->impl).finish();
          });
        },
        // trajectory
        [](void* instance, int32_t which, beslam_trajectory_list* out) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr || out == nullptr) throw std::invalid_argument("trajectory: null argument");
            Backend& b = *self->impl;
            b.abi_trajectory_.clear();
            for (const TrajectoryEntry& e : b.trajectory(which))
              b.abi_trajectory_.push_back({e.frame_index, e.timestamp, toPose(e.T_world_cam)});
            out->entries = b.abi_trajectory_.data();
            out->count = static_cast<uint32_t>(b.abi_trajectory_.size());
            out->element_size = sizeof(beslam_trajectory_entry);
          });
        },
        // map_points
        [](void* instance, beslam_map_point_list* out) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr || out == nullptr) throw std::invalid_argument("map_points: null argument");
            Backend& b = *self->impl;
            b.abi_points_ = b.mapPoints();
            out->points = b.abi_points_.data();
            out->count = b.abi_points_.size();
            out->element_size = sizeof(beslam_map_point);
          });
        }};
    return &table;
  }

 private:
  std::vector<std::string> abi_stage_names_;
  std::vector<beslam_stage_time> abi_stages_;
  std::vector<std::string> abi_counter_names_;
  std::vector<beslam_named_value> abi_counters_;
  std::vector<beslam_keypoint> abi_keypoints_;
  std::vector<beslam_trajectory_entry> abi_trajectory_;
  std::vector<beslam_map_point> abi_points_;
};

}  // namespace beslam::sdk
