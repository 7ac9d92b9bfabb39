// What mask_box and mask_lidar check beyond single settings. Their shared settings are declared once in
// plugins/mask_common/settings.json (each plugin's SETTINGS lists it first, then its own).
#pragma once

#include "beslam/mask_common/mask_builder.hpp"
#include "beslam/sdk/config.hpp"

namespace beslam::mask {

// What no single setting's range can say.
inline void checkCommonOptions(const MaskOptions& o) {
  if (o.contour_params.canny_low > o.contour_params.canny_high)
    throw sdk::ConfigError("canny_low must not exceed canny_high");
}

}  // namespace beslam::mask
