// Mask generator base class: override generate(); write labels into the zero-filled CV_16UC1 mask
// (BESLAM_LABEL_DYNAMIC, or BESLAM_LABEL_STATIC_BASE + track_id for static objects).
#pragma once

#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

class MaskGenerator {
 public:
  static constexpr int32_t kKind = BESLAM_KIND_MASK_GENERATOR;
  virtual ~MaskGenerator() = default;
  virtual void generate(const Frame& frame, const std::vector<beslam_box3d>& boxes, cv::Mat& mask) = 0;

  template <class Impl>
  static const void* functionTable() {
    static const beslam_mask_generator_v1 table = {
        sizeof(beslam_mask_generator_v1), 0,
        [](void* instance, const beslam_frame* frame, const beslam_box_list* boxes,
           beslam_mask_buffer* mask) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr || mask == nullptr || mask->data == nullptr)
              throw std::invalid_argument("generate: null argument");
            cv::Mat mat = toMat(*mask);
            uint16_t* const before = reinterpret_cast<uint16_t*>(mat.data);
            static_cast<MaskGenerator&>(*self->impl).generate(toFrame(frame), copyBoxes(boxes), mat);
            if (reinterpret_cast<uint16_t*>(mat.data) != before)
              throw std::logic_error("mask generator replaced the host's mask buffer instead of writing it");
          });
        }};
    return &table;
  }
};

}  // namespace beslam::sdk
