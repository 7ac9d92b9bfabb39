// motion_bev_tracker: the motion checker plugin, a thin SDK wrapper over beslam::motion::BevTracker
// (bev_tracker.hpp has the method, docs/motion.md the settings and their effect).
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
    std::ostringstream s;
    s << "association " << p.association << ", gate " << p.gate << " m + " << p.gate_per_m << "/m, noise "
      << p.pos_sigma << " m + " << p.pos_sigma_per_m << "/m, ego " << p.ego_speed_noise << " x speed + "
      << p.ego_turn_noise << " x yaw rate x range, dynamic > " << p.dynamic_speed << " m/s, static < " << p.static_speed
      << " m/s, dynamic after " << p.start_frames << " frames (" << p.pull_out_frames << " when parked), static after "
      << p.stop_dwell << " frames";
    context.info(s.str());
  }

  void classify(const beslam::sdk::Frame& frame, const std::optional<Eigen::Isometry3d>& T_world_cam,
                std::vector<beslam_box3d>& boxes) override {
    tracker_.classify(frame.timestamp, T_world_cam, boxes);
  }

  void worldMoved(const Eigen::Isometry3d& S_new_old, double scale) override { tracker_.worldMoved(S_new_old, scale); }

 private:
  beslam::motion::BevTracker tracker_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MotionBevTracker>(kInfo))
