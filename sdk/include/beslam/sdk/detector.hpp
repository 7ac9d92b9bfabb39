// Detector: called once a frame with the input frame; returns the frame's 3D boxes in the camera frame
// (x right, y down, z forward; geometric centre; size = length, width, height; yaw about camera y). Start
// each box from newBox() (no track, motion unknown). The host rejects a box with a non-finite value.
// Call: detect(frame) -> boxes. The C glue is in detail/detector.hpp.
#pragma once

#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

class Detector : public detail::Kind<Detector, BESLAM_KIND_DETECTOR> {
 public:
  virtual ~Detector() = default;
  virtual std::vector<beslam_box3d> detect(const Frame& frame) = 0;

 private:
  friend struct detail::Access;  // the C glue (detail/detector.hpp) keeps here what the host reads
  struct {
    std::vector<beslam_box3d> boxes;  // what the last detect() handed to the host
  } abi_;
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/detector.hpp"
