// C-to-C++ glue of the Reconstructor kind (included by reconstructor.hpp): the beslam_reconstructor_v1 table. Each
// function converts the C views, calls the plugin through detail::call (exceptions become a status) and keeps what it
// returns in storage that lives until the next call.
#pragma once

namespace beslam::sdk {

namespace detail {

template <>
struct Glue<Reconstructor> {
  template <class Impl>
  static const void* table() {
    static const beslam_reconstructor_v1 table = {
        sizeof(beslam_reconstructor_v1), 0,
        [](void* instance, const beslam_keyframe* keyframe, const beslam_frame* frame, const beslam_box_list* boxes,
           const beslam_image_view* mask, beslam_landmark_list* out) -> beslam_status {
          return detail::call<Impl, Reconstructor>(instance, "reconstruct", [&](Reconstructor& r) {
            detail::require("reconstruct", keyframe, out);
            r.abi_landmarks_ =
                r.reconstruct(toKeyframe(*keyframe), toFrame(frame), copyBoxes(boxes), mask ? toMat(*mask) : cv::Mat());
            r.abi_c_landmarks_ = toC(r.abi_landmarks_);
            out->landmarks = r.abi_c_landmarks_.data();
            out->count = static_cast<uint32_t>(r.abi_c_landmarks_.size());
            out->element_size = sizeof(beslam_object_landmark);
          });
        }};
    return &table;
  }
};

}  // namespace detail
}  // namespace beslam::sdk
