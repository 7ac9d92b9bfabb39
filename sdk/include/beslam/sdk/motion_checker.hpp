// Motion checker base class: override classify(); set track_id and motion_state of each box in place.
// T_world_cam is the backend's predicted pose for this frame (empty before the backend has one).
#pragma once

#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

class MotionChecker {
 public:
  static constexpr int32_t kKind = BESLAM_KIND_MOTION_CHECKER;
  virtual ~MotionChecker() = default;
  virtual void classify(const Frame& frame, const std::optional<Eigen::Isometry3d>& T_world_cam,
                        std::vector<beslam_box3d>& boxes) = 0;

  template <class Impl>
  static const void* functionTable() {
    static const beslam_motion_checker_v1 table = {
        sizeof(beslam_motion_checker_v1), 0,
        [](void* instance, const beslam_frame* frame, const beslam_pose* T_world_cam,
           beslam_box_array* boxes) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr || boxes == nullptr) throw std::invalid_argument("classify: null argument");
            std::vector<beslam_box3d> local = copyArray(boxes->boxes, boxes->count, boxes->element_size);
            std::optional<Eigen::Isometry3d> pose;
            if (T_world_cam) pose = toIsometry(*T_world_cam);
            static_cast<MotionChecker&>(*self->impl).classify(toFrame(frame), pose, local);
            if (local.size() != boxes->count)
              throw std::logic_error("motion checker changed the number of boxes");
            writeBoxes(local, *boxes);
          });
        }};
    return &table;
  }
};

}  // namespace beslam::sdk
