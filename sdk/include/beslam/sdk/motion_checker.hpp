// Motion checker: called once a frame with the detector's boxes; sets each box's track_id and
// motion_state (static / dynamic / unknown) in place and keeps the number of boxes. T_world_cam is the
// backend's predicted pose, given only once the backend's world is metric (empty before).
// Call: classify(frame, T_world_cam, boxes). Since ABI 1.7 also worldMoved(S_new_old, scale) when the backend
// moved its world (a loop correction, a change of scale) between two frames: a point placed in the world at
// p_old is at scale * R * p_old + t now, and the next T_world_cam is in the moved world. A checker that keeps
// world positions re-expresses them (the default does nothing). The C glue is in detail/motion_checker.hpp.
#pragma once

#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

class MotionChecker : public detail::Kind<MotionChecker, BESLAM_KIND_MOTION_CHECKER> {
 public:
  virtual ~MotionChecker() = default;
  virtual void classify(const Frame& frame, const std::optional<Eigen::Isometry3d>& T_world_cam,
                        std::vector<beslam_box3d>& boxes) = 0;
  virtual void worldMoved(const Eigen::Isometry3d& /*S_new_old*/, double /*scale*/) {}
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/motion_checker.hpp"
