// The settings mask_box and mask_lidar share, each declared once against MaskOptions, and the check
// that spans two of them. A plugin lists commonSettings() first, then its own.
#pragma once

#include <vector>

#include "beslam/mask_common/mask_builder.hpp"
#include "beslam/sdk/settings.hpp"

namespace beslam::mask {

inline std::vector<sdk::Setting<MaskOptions>> commonSettings() {
  using sdk::nested;
  using sdk::setting;
  return {
      setting(&MaskOptions::margin_px, "margin_px", "2", 0, 100, "pixels added around each projected box polygon"),
      setting(&MaskOptions::near, "near", "0.3", 0.01, 10, "near plane (m): boxes are clipped here before projecting"),
      sdk::choice(
          &MaskOptions::unknown, "unknown_policy", "dynamic",
          {{"dynamic", UnknownPolicy::Dynamic}, {"static", UnknownPolicy::Static}, {"skip", UnknownPolicy::Skip}},
          "boxes of unknown motion: mask as dynamic, as static (needs a track id), or skip"),
      setting(&MaskOptions::contour, "contour", "true", "edge contour refinement (six cubic pieces, equation (3))"),
      nested(&MaskOptions::contour_params,
             setting(&ContourParams::canny_low, "canny_low", "30", 0, 1000, "contour: Canny low threshold")),
      nested(&MaskOptions::contour_params,
             setting(&ContourParams::canny_high, "canny_high", "90", 0, 1000, "contour: Canny high threshold")),
      nested(&MaskOptions::contour_params,
             setting(&ContourParams::min_support, "min_support", "0.3", 0, 1,
                     "contour: a rectangle needs edge points in this fraction of its columns, else it keeps the "
                     "projected outline")),
      nested(&MaskOptions::contour_params, setting(&ContourParams::smooth_weight, "smooth_weight", "3", 0, 100,
                                                   "contour: weight of the gradient-direction term (3)")),
  };
}

// What no single setting's range can say.
inline void checkCommonOptions(const MaskOptions& o) {
  if (o.contour_params.canny_low > o.contour_params.canny_high)
    throw sdk::ConfigError("canny_low must not exceed canny_high");
}

}  // namespace beslam::mask
