// The beslam_detector_v1 table of the Detector kind (see detail/plugin.hpp for how the glue works).
#pragma once

namespace beslam::sdk::detail {

template <class Impl>
const void* table(Tag<Impl>, const Detector*) {
  return makeTable<beslam_detector_v1>(
      [](void* instance, const beslam_frame* frame, beslam_box_list* out) -> beslam_status {
        return call<Impl, Detector>(instance, "detect", [&](Detector& d) {
          require("detect", out);
          auto& abi = Access::buffers(d);
          abi.boxes = d.detect(toFrame(frame));
          out->boxes = abi.boxes.data();
          out->count = static_cast<uint32_t>(abi.boxes.size());
          out->element_size = sizeof(beslam_box3d);
        });
      });
}

}  // namespace beslam::sdk::detail
