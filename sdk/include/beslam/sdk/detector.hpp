// Detector base class: override detect(); return boxes in the camera frame (see beslam/data.h).
#pragma once

#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

// A box with the ABI's neutral defaults: no track, motion unknown, no optional fields.
inline beslam_box3d newBox() {
  beslam_box3d box{};
  box.track_id = -1;
  box.motion_state = BESLAM_MOTION_UNKNOWN;
  return box;
}

class Detector {
 public:
  static constexpr int32_t kKind = BESLAM_KIND_DETECTOR;
  virtual ~Detector() = default;
  virtual std::vector<beslam_box3d> detect(const Frame& frame) = 0;

  template <class Impl>
  static const void* functionTable() {
    static const beslam_detector_v1 table = {
        sizeof(beslam_detector_v1), 0,
        [](void* instance, const beslam_frame* frame, beslam_box_list* out) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr || out == nullptr) throw std::invalid_argument("detect: null argument");
            Detector& d = *self->impl;
            d.abi_boxes_ = d.detect(toFrame(frame));
            out->boxes = d.abi_boxes_.data();
            out->count = static_cast<uint32_t>(d.abi_boxes_.size());
            out->element_size = sizeof(beslam_box3d);
          });
        }};
    return &table;
  }

 private:
  std::vector<beslam_box3d> abi_boxes_;  // what the last detect() handed to the host
};

}  // namespace beslam::sdk
