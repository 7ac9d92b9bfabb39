// Reconstructor base class: override reconstruct(); return the landmarks this keyframe created or updated.
#pragma once

#include "beslam/sdk/landmark.hpp"

namespace beslam::sdk {

class Reconstructor {
 public:
  static constexpr int32_t kKind = BESLAM_KIND_RECONSTRUCTOR;
  virtual ~Reconstructor() = default;
  virtual std::vector<Landmark> reconstruct(const Keyframe& keyframe, const Frame& frame,
                                            const std::vector<beslam_box3d>& boxes, const cv::Mat& mask) = 0;

  template <class Impl>
  static const void* functionTable() {
    static const beslam_reconstructor_v1 table = {
        sizeof(beslam_reconstructor_v1), 0,
        [](void* instance, const beslam_keyframe* keyframe, const beslam_frame* frame,
           const beslam_box_list* boxes, const beslam_image_view* mask,
           beslam_landmark_list* out) -> beslam_status {
          auto* self = static_cast<detail::Instance<Impl>*>(instance);
          return detail::guarded(self ? &self->context : nullptr, [&] {
            if (self == nullptr || keyframe == nullptr || out == nullptr)
              throw std::invalid_argument("reconstruct: null argument");
            Reconstructor& r = *self->impl;
            r.abi_landmarks_ = r.reconstruct(toKeyframe(*keyframe), toFrame(frame), copyBoxes(boxes),
                                             mask ? toMat(*mask) : cv::Mat());
            r.abi_c_landmarks_ = toC(r.abi_landmarks_);
            out->landmarks = r.abi_c_landmarks_.data();
            out->count = static_cast<uint32_t>(r.abi_c_landmarks_.size());
            out->element_size = sizeof(beslam_object_landmark);
          });
        }};
    return &table;
  }

 private:
  std::vector<Landmark> abi_landmarks_;
  std::vector<beslam_object_landmark> abi_c_landmarks_;
};

}  // namespace beslam::sdk
