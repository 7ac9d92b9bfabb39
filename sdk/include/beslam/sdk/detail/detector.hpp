// C-to-C++ glue of the Detector kind (included by detector.hpp): the beslam_detector_v1 table. Each function
// converts the C views, calls the plugin through detail::call (exceptions become a status) and keeps what
// it returns in storage that lives until the next call.
#pragma once

namespace beslam::sdk {

namespace detail {

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

}  // namespace detail
}  // namespace beslam::sdk
