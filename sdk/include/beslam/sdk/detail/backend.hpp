// The beslam_backend_v1 table of the Backend kind (see detail/plugin.hpp for how the glue works).
#pragma once

namespace beslam::sdk::detail {

template <class Impl>
const void* table(Tag<Impl>, const Backend*) {
  return makeTable<beslam_backend_v1>(
      // predict_pose
      [](void* instance, const beslam_frame* frame, beslam_pose* T_world_cam, int32_t* valid) -> beslam_status {
        return call<Impl, Backend>(instance, "predict_pose", [&](Backend& b) {
          require("predict_pose", T_world_cam, valid);
          const auto pose = b.predictPose(toFrame(frame));
          *valid = pose ? 1 : 0;
          if (pose) *T_world_cam = toPose(*pose);
        });
      },
      // track
      [](void* instance, const beslam_frame* frame, const beslam_image_view* mask, const beslam_box_list* boxes,
         beslam_track_result* result) -> beslam_status {
        return call<Impl, Backend>(instance, "track", [&](Backend& b) {
          require("track", result);
          auto& abi = Access::buffers(b);
          const TrackResult r = b.track(toFrame(frame), mask ? toMat(*mask) : cv::Mat(), copyBoxes(boxes));
          abi.stages.set(r.stage_ms);
          abi.counters.set(r.counters);
          beslam_track_result c{};
          c.struct_size = sizeof(c);
          c.state = r.state;
          c.is_keyframe = r.is_keyframe ? 1 : 0;
          c.tracked_points = r.tracked_points;
          c.keyframe_id = r.keyframe_id;
          c.T_world_cam = toPose(r.T_world_cam);
          c.stage_times = abi.stages.data();
          c.stage_count = abi.stages.size();
          c.world_scale = r.world_is_metric ? BESLAM_WORLD_SCALE_METRIC : BESLAM_WORLD_SCALE_UNKNOWN;
          c.counters = abi.counters.data();
          c.counter_count = abi.counters.size();
          abi.keypoints = r.keypoints;
          c.keypoints = abi.keypoints.empty() ? nullptr : abi.keypoints.data();
          c.keypoint_count = static_cast<uint32_t>(abi.keypoints.size());
          c.keypoint_size = sizeof(beslam_keypoint);
          abi.keyframe_points.clear();
          for (const KeyframePoint& p : r.keyframe_points) abi.keyframe_points.push_back(toC(p));
          c.keyframe_points = abi.keyframe_points.empty() ? nullptr : abi.keyframe_points.data();
          c.keyframe_point_count = static_cast<uint32_t>(abi.keyframe_points.size());
          c.keyframe_point_size = sizeof(beslam_keyframe_point);
          if (r.S_new_old) {
            c.world_moved = 1;
            c.world_change_scale = r.world_change_scale;
            c.S_new_old = toPose(*r.S_new_old);
          }
          std::memcpy(result, &c, std::min<size_t>(result->struct_size ? result->struct_size : sizeof(c), sizeof(c)));
        });
      },
      // add_landmarks
      [](void* instance, const beslam_landmark_list* landmarks) -> beslam_status {
        return call<Impl, Backend>(instance, "add_landmarks", [&](Backend& b) { b.addLandmarks(fromC(landmarks)); });
      },
      // finish
      [](void* instance) -> beslam_status {
        return call<Impl, Backend>(instance, "finish", [&](Backend& b) { b.finish(); });
      },
      // trajectory
      [](void* instance, int32_t which, beslam_trajectory_list* out) -> beslam_status {
        return call<Impl, Backend>(instance, "trajectory", [&](Backend& b) {
          require("trajectory", out);
          auto& abi = Access::buffers(b);
          abi.trajectory.clear();
          for (const TrajectoryEntry& e : b.trajectory(which))
            abi.trajectory.push_back({e.frame_index, e.timestamp, toPose(e.T_world_cam)});
          out->entries = abi.trajectory.data();
          out->count = static_cast<uint32_t>(abi.trajectory.size());
          out->element_size = sizeof(beslam_trajectory_entry);
        });
      },
      // map_points
      [](void* instance, beslam_map_point_list* out) -> beslam_status {
        return call<Impl, Backend>(instance, "map_points", [&](Backend& b) {
          require("map_points", out);
          auto& abi = Access::buffers(b);
          abi.points = b.mapPoints();
          out->points = abi.points.data();
          out->count = abi.points.size();
          out->element_size = sizeof(beslam_map_point);
        });
      },
      // prepare (ABI 1.4)
      [](void* instance, const beslam_frame* frame) -> beslam_status {
        return call<Impl, Backend>(instance, "prepare", [&](Backend& b) { b.prepare(toFrame(frame)); });
      });
}

}  // namespace beslam::sdk::detail
