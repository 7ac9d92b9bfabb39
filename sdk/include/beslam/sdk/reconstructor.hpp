// Reconstructor: called on each new keyframe of a metric world with the keyframe, its frame, boxes and
// mask; returns the object landmarks this keyframe created or updated (world frame, x heading, y left,
// z up), which the host hands to the backend. Calls: reconstruct(keyframe, frame, boxes, mask) per keyframe
// (keyframe.points: the map points it observes), finish() once at the end. A landmark returned again
// (same track_id) replaces the earlier one; `removed` drops it. The host writes objects.json and the
// meshes (objects/) from each object's latest landmark.
// The C glue is in detail/reconstructor.hpp.
#pragma once

#include "beslam/sdk/landmark.hpp"
#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

class Reconstructor : public detail::Kind<Reconstructor, BESLAM_KIND_RECONSTRUCTOR> {
 public:
  virtual ~Reconstructor() = default;
  virtual std::vector<Landmark> reconstruct(const Keyframe& keyframe, const Frame& frame,
                                            const std::vector<beslam_box3d>& boxes, const cv::Mat& mask) = 0;
  // The run is over: last updates (a final refinement), applied like reconstruct()'s. Optional.
  virtual std::vector<Landmark> finish() { return {}; }

 private:
  friend struct detail::Access;  // the C glue (detail/reconstructor.hpp) keeps here what the host reads
  struct {
    std::vector<Landmark> landmarks;
    std::vector<beslam_object_landmark> c_landmarks;  // C views of landmarks
  } abi_;
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/reconstructor.hpp"
