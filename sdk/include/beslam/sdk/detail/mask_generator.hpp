// The beslam_mask_generator_v1 table of the MaskGenerator kind (see detail/plugin.hpp for how the glue works).
#pragma once

namespace beslam::sdk::detail {

template <class Impl>
const void* table(Tag<Impl>, const MaskGenerator*) {
  return makeTable<beslam_mask_generator_v1>([](void* instance, const beslam_frame* frame, const beslam_box_list* boxes,
                                                beslam_mask_buffer* mask) -> beslam_status {
    return call<Impl, MaskGenerator>(instance, "generate", [&](MaskGenerator& m) {
      require("generate", mask, mask ? mask->data : nullptr);
      cv::Mat mat = toMat(*mask);
      uint16_t* const before = reinterpret_cast<uint16_t*>(mat.data);
      m.generate(toFrame(frame), copyBoxes(boxes), mat);
      if (reinterpret_cast<uint16_t*>(mat.data) != before)
        throw std::logic_error("mask generator replaced the host's mask buffer instead of writing it");
    });
  });
}

}  // namespace beslam::sdk::detail
