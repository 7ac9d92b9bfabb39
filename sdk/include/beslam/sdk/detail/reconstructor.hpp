// The beslam_reconstructor_v1 table of the Reconstructor kind (see detail/plugin.hpp for how the glue works).
#pragma once

namespace beslam::sdk::detail {

template <class Impl>
const void* table(Tag<Impl>, const Reconstructor*) {
  return makeTable<beslam_reconstructor_v1>(
      [](void* instance, const beslam_keyframe* keyframe, const beslam_frame* frame, const beslam_box_list* boxes,
         const beslam_image_view* mask, beslam_landmark_list* out) -> beslam_status {
        return call<Impl, Reconstructor>(instance, "reconstruct", [&](Reconstructor& r) {
          require("reconstruct", keyframe, out);
          auto& abi = Access::buffers(r);
          abi.landmarks =
              r.reconstruct(toKeyframe(*keyframe), toFrame(frame), copyBoxes(boxes), mask ? toMat(*mask) : cv::Mat());
          abi.c_landmarks = toC(abi.landmarks);
          out->landmarks = abi.c_landmarks.data();
          out->count = static_cast<uint32_t>(abi.c_landmarks.size());
          out->element_size = sizeof(beslam_object_landmark);
        });
      },
      [](void* instance, beslam_landmark_list* out) -> beslam_status {
        return call<Impl, Reconstructor>(instance, "finish", [&](Reconstructor& r) {
          require("finish", out);
          auto& abi = Access::buffers(r);
          abi.landmarks = r.finish();
          abi.c_landmarks = toC(abi.landmarks);
          out->landmarks = abi.c_landmarks.data();
          out->count = static_cast<uint32_t>(abi.c_landmarks.size());
          out->element_size = sizeof(beslam_object_landmark);
        });
      });
}

}  // namespace beslam::sdk::detail
