// motion_bev_tracker: the motion checker plugin, a thin SDK wrapper over beslam::motion::BevTracker
// (bev_tracker.hpp has the method, docs/motion.md the settings and their effect).
#include <sstream>

#include "beslam/motion/bev_tracker.hpp"
#include "beslam/sdk/sdk.hpp"

namespace {

using beslam::motion::Params;
using beslam::sdk::setting;

// Each setting once: its schema entry and the Params member it sets (docs/motion.md has their effect).
// clang-format off: one setting a line
const beslam::sdk::Settings<Params> kSettings{
    setting(&Params::association, "association", "distance", "distance|iou",
            "cost of the global assignment: BEV centre distance or 1 - BEV IoU"),
    setting(&Params::gate, "gate", "2.0", 0.01, 100, "m: largest BEV distance of a match at range 0"),
    setting(&Params::gate_per_m, "gate_per_m", "0.03", 0, 10, "m of gate added per metre of range"),
    setting(&Params::min_iou, "min_iou", "0.01", 0.0001, 0.99, "association iou: smallest BEV IoU of a match"),
    setting(&Params::match_across_classes, "match_across_classes", "false",
            "let any class match any other (car, van and truck always match)"),
    setting(&Params::accel_sigma, "accel_sigma", "4.0", 0.01, 100, "m/s^2: Kalman process noise (white acceleration)"),
    setting(&Params::pos_sigma, "pos_sigma", "0.1", 0.001, 100, "m: detection position noise at range 0"),
    setting(&Params::pos_sigma_per_m, "pos_sigma_per_m", "0.005", 0, 10,
            "m of position noise per metre of range (depth and bearing uncertainty)"),
    setting(&Params::velocity_sigma, "velocity_sigma", "1.0", 0.001, 100, "m/s: noise of a detector's own velocity"),
    setting(&Params::ego_speed_noise, "ego_speed_noise", "0.01", 0, 1,
            "apparent speed of a parked car per m/s of ego speed (pose drift)"),
    setting(&Params::ego_turn_noise, "ego_turn_noise", "0.05", 0, 1,
            "apparent lateral speed of a parked car per rad/s of ego yaw rate and metre of range (heading-rate error)"),
    setting(&Params::max_miss_time, "max_miss_time", "1.0", 0, 100,
            "s a track survives without detections (occlusion)"),
    setting(&Params::window_dynamic, "window_dynamic", "0.5", 0.01, 100, "s of track history behind dynamic evidence"),
    setting(&Params::window_static, "window_static", "1.5", 0.01, 100, "s of track history behind static evidence"),
    setting(&Params::min_observations, "min_observations", "3", 2, 1000,
            "detections in the window before a track is decided"),
    setting(&Params::max_residual, "max_residual", "2.0", 0.01, 100,
            "a window whose line-fit residual exceeds this many noise sigmas gives no evidence"),
    setting(&Params::pose_jitter, "pose_jitter", "false",
            "measure how far the poses leave a steady path (a backend correcting itself) and add it to every "
            "position's noise"),
    setting(&Params::init_velocity_sigma, "init_velocity_sigma", "5.0", 0.01, 100,
            "m/s: velocity uncertainty of a new track"),
    setting(&Params::dynamic_speed, "dynamic_speed", "0.3", 0, 100,
            "m/s: a car this slow is parked; dynamic evidence needs speed less z_dynamic standard errors above it"),
    setting(&Params::static_speed, "static_speed", "1.0", 0.001, 100,
            "m/s: a car this fast moves; static evidence needs speed plus z_static standard errors below it"),
    setting(&Params::z_dynamic, "z_dynamic", "3.0", 0, 100, "standard errors a dynamic decision must clear"),
    setting(&Params::z_static, "z_static", "2.0", 0, 100, "standard errors a static decision must clear"),
    setting(&Params::displacement_margin, "displacement_margin", "0.75", 0, 100,
            "m: a parked track that leaves its parked position by this (plus z_dynamic sigmas) moves"),
    setting(&Params::anchor_frames, "anchor_frames", "30", 1, 10000, "frames averaged into a parked track's position"),
    setting(&Params::start_frames, "start_frames", "2", 1, 1000,
            "dynamic frames in a row that turn a static track dynamic"),
    setting(&Params::stop_dwell, "stop_dwell", "5", 1, 1000, "static frames in a row that turn a dynamic track static"),
    setting(&Params::max_range, "max_range", "200", 0.1, 1e6, "m: farther boxes are tracked but reported unknown"),
};
// clang-format on

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
      << " m/s, dwell " << p.stop_dwell << " frames";
    context.info(s.str());
  }

  void classify(const beslam::sdk::Frame& frame, const std::optional<Eigen::Isometry3d>& T_world_cam,
                std::vector<beslam_box3d>& boxes) override {
    tracker_.classify(frame.timestamp, T_world_cam, boxes);
  }

 private:
  beslam::motion::BevTracker tracker_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MotionBevTracker>(kInfo))
