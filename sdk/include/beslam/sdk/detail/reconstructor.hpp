// The beslam_reconstructor_v1 table of the Reconstructor kind (see detail/plugin.hpp for how the glue works).
#pragma once

namespace beslam::sdk::detail {

// Keeps `landmarks` and their C views in the instance's buffers (until its next call) and points `out` at them.
template <class Buffers>
void handOver(Buffers& abi, std::vector<Landmark> landmarks, beslam_landmark_list* out) {
  abi.landmarks = std::move(landmarks);
  abi.c_landmarks = toC(abi.landmarks);
  out->landmarks = abi.c_landmarks.data();
  out->count = static_cast<uint32_t>(abi.c_landmarks.size());
  out->element_size = sizeof(beslam_object_landmark);
}

template <class Impl>
const void* table(Tag<Impl>, const Reconstructor*) {
  return makeTable<beslam_reconstructor_v1>(
      [](void* instance, const beslam_keyframe* keyframe, const beslam_frame* frame, const beslam_box_list* boxes,
         const beslam_image_view* mask, beslam_landmark_list* out) -> beslam_status {
        return call<Impl, Reconstructor>(instance, "reconstruct", [&](Reconstructor& r) {
          require("reconstruct", keyframe, out);
          handOver(
              Access::buffers(r),
              r.reconstruct(toKeyframe(*keyframe), toFrame(frame), copyBoxes(boxes), mask ? toMat(*mask) : cv::Mat()),
              out);
        });
      },
      [](void* instance, beslam_landmark_list* out) -> beslam_status {
        return call<Impl, Reconstructor>(instance, "finish", [&](Reconstructor& r) {
          require("finish", out);
          handOver(Access::buffers(r), r.finish(), out);
        });
      });
}

}  // namespace beslam::sdk::detail
