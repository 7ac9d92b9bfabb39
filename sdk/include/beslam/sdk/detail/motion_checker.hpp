// The beslam_motion_checker_v1 table of the MotionChecker kind (see detail/plugin.hpp for how the glue works).
#pragma once

namespace beslam::sdk::detail {

template <class Impl>
const void* table(Tag<Impl>, const MotionChecker*) {
  return makeTable<beslam_motion_checker_v1>(
      [](void* instance, const beslam_frame* frame, const beslam_pose* T_world_cam,
         beslam_box_array* boxes) -> beslam_status {
        return call<Impl, MotionChecker>(instance, "classify", [&](MotionChecker& m) {
          require("classify", boxes);
          std::vector<beslam_box3d> local = copyArray(boxes->boxes, boxes->count, boxes->element_size);
          std::optional<Eigen::Isometry3d> pose;
          if (T_world_cam) pose = toIsometry(*T_world_cam);
          m.classify(toFrame(frame), pose, local);
          if (local.size() != boxes->count) throw std::logic_error("motion checker changed the number of boxes");
          writeBoxes(local, *boxes);
        });
      },
      [](void* instance, const beslam_pose* S_new_old, double scale) -> beslam_status {
        return call<Impl, MotionChecker>(instance, "world_moved", [&](MotionChecker& m) {
          require("world_moved", S_new_old);
          m.worldMoved(toIsometry(*S_new_old), scale);
        });
      });
}

}  // namespace beslam::sdk::detail
