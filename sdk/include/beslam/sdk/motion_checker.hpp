// Motion checker: called once a frame with the detector's boxes; sets each box's track_id and
// motion_state (static / dynamic / unknown) in place and keeps the number of boxes. T_world_cam is the
// backend's predicted pose, given only once the backend's world is metric (empty before).
// Call: classify(frame, T_world_cam, boxes). The C glue is in detail/motion_checker.hpp.
#pragma once

#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

class MotionChecker : public detail::Kind<MotionChecker, BESLAM_KIND_MOTION_CHECKER> {
 public:
  virtual ~MotionChecker() = default;
  virtual void classify(const Frame& frame, const std::optional<Eigen::Isometry3d>& T_world_cam,
                        std::vector<beslam_box3d>& boxes) = 0;
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/motion_checker.hpp"
