// motion_bev_tracker: the motion checker plugin, a thin SDK wrapper over beslam::motion::BevTracker
// (bev_tracker.hpp has the method, docs/motion.md the settings and their effect).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>

#include "beslam/motion/bev_tracker.hpp"
#include "beslam/sdk/sdk.hpp"
#include "motion_bev_tracker_settings.hpp"  // kSettings, from settings.json

namespace {

using beslam::motion::Params;

const beslam::sdk::PluginInfo kInfo(
    "motion_bev_tracker", "BEV motion tracker",
    "Tracks boxes in the world BEV (Kalman + Hungarian) and marks them static, dynamic or unknown", {1, 0, 0},
    kSettings);

Params paramsFrom(const beslam::sdk::Config& config) {
  const Params p = kSettings.read(config);
  const std::string problem = p.validate();
  if (!problem.empty()) throw beslam::sdk::ConfigError(problem);
  return p;
}

class MotionBevTracker : public beslam::sdk::MotionChecker {
 public:
  MotionBevTracker(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : tracker_(paramsFrom(config)) {
    const Params& p = tracker_.params();
    if (p.parallax) {
      const beslam_camera& K = context.camera();
      if (!(K.fx > 0) || !(K.fy > 0))
        throw beslam::sdk::ConfigError("parallax needs the camera's intrinsics, which this dataset does not give");
      parallax_.emplace(p.parallax_check, K.fx, K.fy, K.cx, K.cy);
    }
    std::ostringstream s;
    s << "association " << p.association << ", gate " << p.gate << " m + " << p.gate_per_m << "/m, noise "
      << p.pos_sigma << " m + " << p.pos_sigma_per_m << "/m, ego " << p.ego_speed_noise << " x speed + "
      << p.ego_turn_noise << " x yaw rate x range, dynamic > " << p.dynamic_speed << " m/s, static < " << p.static_speed
      << " m/s, dynamic after " << p.start_frames << " frames (" << p.pull_out_frames << " when parked), static after "
      << p.stop_dwell << " frames";
    if (p.parallax) s << ", parallax evidence within " << p.parallax_tolerance << " of the lifted range";
    context.info(s.str());
  }

  void classify(const beslam::sdk::Frame& frame, const std::optional<Eigen::Isometry3d>& T_world_cam,
                std::vector<beslam_box3d>& boxes) override {
    tracker_.classify(frame.timestamp, T_world_cam, boxes);
    if (!parallax_) return;
    // The ids are this frame's: parallax measured now is evidence now.
    for (const beslam::motion::ParallaxMeasurement& m : parallax_->update(frame.gray, T_world_cam, boxes)) {
      const std::optional<int32_t> state = tracker_.parallaxEvidence(m.track_id, m.depth_ratio);
      if (debug_)  // developers: every parallax measurement
        std::fprintf(stderr, "frame %ld: track %d parallax depth ratio %.3f from %d points\n",
                     static_cast<long>(frame.index), m.track_id, m.depth_ratio, m.points);
      if (!state) continue;
      for (beslam_box3d& b : boxes)
        if (b.track_id == m.track_id && inRange(b)) b.motion_state = *state;
    }
  }

  void worldMoved(const Eigen::Isometry3d& S_new_old, double scale) override { tracker_.worldMoved(S_new_old, scale); }

 private:
  bool inRange(const beslam_box3d& b) const {
    return std::hypot(b.center_cam[0], b.center_cam[2]) <= tracker_.params().max_range;
  }
  beslam::motion::BevTracker tracker_;
  std::optional<beslam::motion::ParallaxCheck> parallax_;
  bool debug_ = std::getenv("BESLAM_MOTION_DEBUG") != nullptr;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MotionBevTracker>(kInfo))
