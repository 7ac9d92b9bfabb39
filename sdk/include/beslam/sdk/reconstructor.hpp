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
  friend struct detail::Access;  // the C glue (detail/reconstructor.hpp) keeps here what the host reads
  struct {
    std::vector<Landmark> landmarks;
    std::vector<beslam_object_landmark> c_landmarks;  // C views of landmarks
  } abi_;
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/reconstructor.hpp"
