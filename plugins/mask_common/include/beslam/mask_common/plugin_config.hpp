// Configuration keys shared by mask_box and mask_lidar (schema entries and their reading into MaskOptions).
#pragma once

#include "beslam/mask_common/mask_builder.hpp"
#include "beslam/sdk/config.hpp"

namespace beslam::mask {

#define BESLAM_MASK_COMMON_FIELDS                                                                              \
  beslam::sdk::field::Double("margin_px", "2", 0, 100, "pixels added around each projected box polygon"),       \
      beslam::sdk::field::Double("near", "0.3", 0.01, 10, "near plane (m): boxes are clipped here before projecting"), \
      beslam::sdk::field::String("unknown_policy", "dynamic", "dynamic|static|skip",                             \
                                 "boxes of unknown motion: mask as dynamic, as static (needs a track id), or skip"), \
      beslam::sdk::field::Bool("contour", "true", "edge contour refinement (six cubic pieces, equation (3))"),   \
      beslam::sdk::field::Double("canny_low", "30", 0, 1000, "contour: Canny low threshold"),                  \
      beslam::sdk::field::Double("canny_high", "90", 0, 1000, "contour: Canny high threshold"),                \
      beslam::sdk::field::Double("min_support", "0.3", 0, 1,                                                   \
                                 "contour: a rectangle needs edge points in this fraction of its columns, else it keeps the projected outline"), \
      beslam::sdk::field::Double("smooth_weight", "3", 0, 100, "contour: weight of the gradient-direction term (3)")

inline void readCommonOptions(const sdk::Config& config, MaskOptions& o) {
  o.margin_px = config.getDouble("margin_px");
  o.near = config.getDouble("near");
  try {
    o.unknown = parseUnknownPolicy(config.getString("unknown_policy"));
  } catch (const std::invalid_argument& e) {
    throw sdk::ConfigError(e.what());
  }
  o.contour = config.getBool("contour");
  o.contour_params.canny_low = config.getDouble("canny_low");
  o.contour_params.canny_high = config.getDouble("canny_high");
  if (o.contour_params.canny_low > o.contour_params.canny_high)
    throw sdk::ConfigError("canny_low must not exceed canny_high");
  o.contour_params.min_support = config.getDouble("min_support");
  o.contour_params.smooth_weight = config.getDouble("smooth_weight");
}

}  // namespace beslam::mask
