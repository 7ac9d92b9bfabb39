// C-to-C++ glue of the Detector kind (included by detector.hpp): the beslam_detector_v1 table. Each function
// converts the C views, calls the plugin through detail::call (exceptions become a status) and keeps what
// it returns in storage that lives until the next call.
#pragma once

namespace beslam::sdk {

namespace detail {

template <>
struct Glue<Detector> {
  template <class Impl>
  static const void* table() {
    static const beslam_detector_v1 table = {
        sizeof(beslam_detector_v1), 0,
        [](void* instance, const beslam_frame* frame, beslam_box_list* out) -> beslam_status {
          return detail::call<Impl, Detector>(instance, "detect", [&](Detector& d) {
            detail::require("detect", out);
            d.abi_boxes_ = d.detect(toFrame(frame));
            out->boxes = d.abi_boxes_.data();
            out->count = static_cast<uint32_t>(d.abi_boxes_.size());
            out->element_size = sizeof(beslam_box3d);
          });
        }};
    return &table;
  }
};

}  // namespace detail
}  // namespace beslam::sdk
