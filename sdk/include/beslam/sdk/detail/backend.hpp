// C-to-C++ glue of the Backend kind (included by backend.hpp): the beslam_backend_v1 table. Each function
// converts the C views, calls the plugin through detail::call (exceptions become a status) and keeps what
// it returns in storage that lives until the next call.
#pragma once

namespace beslam::sdk {

namespace detail {

template <>
struct Glue<Backend> {
  template <class Impl>
  static const void* table() {
    static const beslam_backend_v1 table = {
        sizeof(beslam_backend_v1), 0,
        // predict_pose
        [](void* instance, const beslam_frame* frame, beslam_pose* T_world_cam, int32_t* valid) -> beslam_status {
          return detail::call<Impl, Backend>(instance, "predict_pose", [&](Backend& b) {
            detail::require("predict_pose", T_world_cam, valid);
            const auto pose = b.predictPose(toFrame(frame));
            *valid = pose ? 1 : 0;
            if (pose) *T_world_cam = toPose(*pose);
          });
        },
        // track
        [](void* instance, const beslam_frame* frame, const beslam_image_view* mask, const beslam_box_list* boxes,
           beslam_track_result* result) -> beslam_status {
          return detail::call<Impl, Backend>(instance, "track", [&](Backend& b) {
            detail::require("track", result);
            const TrackResult r = b.track(toFrame(frame), mask ? toMat(*mask) : cv::Mat(), copyBoxes(boxes));
            b.abi_stages_.set(r.stage_ms);
            b.abi_counters_.set(r.counters);
            beslam_track_result c{};
            c.struct_size = sizeof(c);
            c.state = r.state;
            c.is_keyframe = r.is_keyframe ? 1 : 0;
            c.tracked_points = r.tracked_points;
            c.keyframe_id = r.keyframe_id;
            c.T_world_cam = toPose(r.T_world_cam);
            c.stage_times = b.abi_stages_.data();
            c.stage_count = b.abi_stages_.size();
            c.world_scale = r.world_is_metric ? BESLAM_WORLD_SCALE_METRIC : BESLAM_WORLD_SCALE_UNKNOWN;
            c.counters = b.abi_counters_.data();
            c.counter_count = b.abi_counters_.size();
            std::memcpy(result, &c, std::min<size_t>(result->struct_size ? result->struct_size : sizeof(c), sizeof(c)));
          });
        },
        // add_landmarks
        [](void* instance, const beslam_landmark_list* landmarks) -> beslam_status {
          return detail::call<Impl, Backend>(instance, "add_landmarks",
                                             [&](Backend& b) { b.addLandmarks(fromC(landmarks)); });
        },
        // finish
        [](void* instance) -> beslam_status {
          return detail::call<Impl, Backend>(instance, "finish", [&](Backend& b) { b.finish(); });
        },
        // trajectory
        [](void* instance, int32_t which, beslam_trajectory_list* out) -> beslam_status {
          return detail::call<Impl, Backend>(instance, "trajectory", [&](Backend& b) {
            detail::require("trajectory", out);
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
          return detail::call<Impl, Backend>(instance, "map_points", [&](Backend& b) {
            detail::require("map_points", out);
            b.abi_points_ = b.mapPoints();
            out->points = b.abi_points_.data();
            out->count = b.abi_points_.size();
            out->element_size = sizeof(beslam_map_point);
          });
        }};
    return &table;
  }
};

}  // namespace detail
}  // namespace beslam::sdk
