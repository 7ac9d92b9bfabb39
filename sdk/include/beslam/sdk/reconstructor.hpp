// Reconstructor: called on each new keyframe of a metric world with the keyframe, its frame, boxes and
// mask; returns the object landmarks this keyframe created or updated (world frame, x heading, y left,
// z up), which the host hands to the backend. Call: reconstruct(keyframe, frame, boxes, mask).
// The C glue is in detail/reconstructor.hpp.
#pragma once

#include "beslam/sdk/landmark.hpp"

namespace beslam::sdk {

class Reconstructor : public detail::Kind<Reconstructor, BESLAM_KIND_RECONSTRUCTOR> {
 public:
  virtual ~Reconstructor() = default;
  virtual std::vector<Landmark> reconstruct(const Keyframe& keyframe, const Frame& frame,
                                            const std::vector<beslam_box3d>& boxes, const cv::Mat& mask) = 0;

 private:
  friend struct detail::Glue<Reconstructor>;  // the C glue (detail/reconstructor.hpp) fills the buffers below
  std::vector<Landmark> abi_landmarks_;
  std::vector<beslam_object_landmark> abi_c_landmarks_;
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/reconstructor.hpp"
