// Mask generator: called once a frame with the frame and the classified boxes; writes labels into the
// host's zero-filled CV_16UC1 mask in place (never replace the Mat): BESLAM_LABEL_DYNAMIC (1) where
// features must not go, BESLAM_LABEL_STATIC_BASE (1000) + track id on a static object, 0 elsewhere.
// Call: generate(frame, boxes, mask). The C glue is in detail/mask_generator.hpp.
#pragma once

#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

class MaskGenerator : public detail::Kind<MaskGenerator, BESLAM_KIND_MASK_GENERATOR> {
 public:
  virtual ~MaskGenerator() = default;
  virtual void generate(const Frame& frame, const std::vector<beslam_box3d>& boxes, cv::Mat& mask) = 0;
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/mask_generator.hpp"
