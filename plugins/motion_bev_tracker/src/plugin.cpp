// motion_bev_tracker: the motion checker plugin, a thin SDK wrapper over beslam::motion::BevTracker
// (bev_tracker.hpp has the method, docs/motion.md the settings and their effect).
#include <sstream>

#include "beslam/motion/bev_tracker.hpp"
#include "beslam/sdk/sdk.hpp"

namespace {

namespace field = beslam::sdk::field;
using beslam::motion::Params;

const beslam_config_field kFields[] = {
    field::String("association", "distance", "distance|iou", "cost of the global assignment: BEV centre distance or 1 - BEV IoU"),
    field::Double("gate", "2.0", 0.01, 100, "m: largest BEV distance of a match at range 0"),
    field::Double("gate_per_m", "0.03", 0, 10, "m of gate added per metre of range"),
    field::Double("min_iou", "0.01", 0.0001, 0.99, "association iou: smallest BEV IoU of a match"),
    field::Bool("match_across_classes", "false", "let any class match any other (car, van and truck always match)"),
    field::Double("accel_sigma", "4.0", 0.01, 100, "m/s^2: Kalman process noise (white acceleration)"),
    field::Double("pos_sigma", "0.1", 0.001, 100, "m: detection position noise at range 0"),
    field::Double("pos_sigma_per_m", "0.005", 0, 10, "m of position noise per metre of range (depth and bearing uncertainty)"),
    field::Double("velocity_sigma", "1.0", 0.001, 100, "m/s: noise of a detector's own velocity"),
    field::Double("ego_speed_noise", "0.01", 0, 1, "apparent speed of a parked car per m/s of ego speed (pose drift)"),
    field::Double("ego_turn_noise", "0.05", 0, 1, "apparent lateral speed of a parked car per rad/s of ego yaw rate and metre of range (heading-rate error)"),
    field::Double("max_miss_time", "1.0", 0, 100, "s a track survives without detections (occlusion)"),
    field::Double("window_dynamic", "0.5", 0.01, 100, "s of track history behind dynamic evidence"),
    field::Double("window_static", "1.5", 0.01, 100, "s of track history behind static evidence"),
    field::Int("min_observations", "3", 2, 1000, "detections in the window before a track is decided"),
    field::Double("max_residual", "2.0", 0.01, 100, "a window whose line-fit residual exceeds this many noise sigmas gives no evidence"),
    field::Double("init_velocity_sigma", "5.0", 0.01, 100, "m/s: velocity uncertainty of a new track"),
    field::Double("dynamic_speed", "0.3", 0, 100, "m/s: a car this slow is parked; dynamic evidence needs speed less z_dynamic standard errors above it"),
    field::Double("static_speed", "1.0", 0.001, 100, "m/s: a car this fast moves; static evidence needs speed plus z_static standard errors below it"),
    field::Double("z_dynamic", "3.0", 0, 100, "standard errors a dynamic decision must clear"),
    field::Double("z_static", "2.0", 0, 100, "standard errors a static decision must clear"),
    field::Double("displacement_margin", "0.75", 0, 100, "m: a parked track that leaves its parked position by this (plus z_dynamic sigmas) moves"),
    field::Int("anchor_frames", "30", 1, 10000, "frames averaged into a parked track's position"),
    field::Int("start_frames", "2", 1, 1000, "dynamic frames in a row that turn a static track dynamic"),
    field::Int("stop_dwell", "5", 1, 1000, "static frames in a row that turn a dynamic track static"),
    field::Double("max_range", "200", 0.1, 1e6, "m: farther boxes are tracked but reported unknown"),
};

Params paramsFrom(const beslam::sdk::Config& c) {
  Params p;
  p.association = c.getString("association");
  p.gate = c.getDouble("gate");
  p.gate_per_m = c.getDouble("gate_per_m");
  p.min_iou = c.getDouble("min_iou");
  p.match_across_classes = c.getBool("match_across_classes");
  p.accel_sigma = c.getDouble("accel_sigma");
  p.pos_sigma = c.getDouble("pos_sigma");
  p.pos_sigma_per_m = c.getDouble("pos_sigma_per_m");
  p.velocity_sigma = c.getDouble("velocity_sigma");
  p.ego_speed_noise = c.getDouble("ego_speed_noise");
  p.ego_turn_noise = c.getDouble("ego_turn_noise");
  p.max_miss_time = c.getDouble("max_miss_time");
  p.window_dynamic = c.getDouble("window_dynamic");
  p.window_static = c.getDouble("window_static");
  p.min_observations = static_cast<int>(c.getInt("min_observations"));
  p.max_residual = c.getDouble("max_residual");
  p.init_velocity_sigma = c.getDouble("init_velocity_sigma");
  p.dynamic_speed = c.getDouble("dynamic_speed");
  p.static_speed = c.getDouble("static_speed");
  p.z_dynamic = c.getDouble("z_dynamic");
  p.z_static = c.getDouble("z_static");
  p.displacement_margin = c.getDouble("displacement_margin");
  p.anchor_frames = static_cast<int>(c.getInt("anchor_frames"));
  p.start_frames = static_cast<int>(c.getInt("start_frames"));
  p.stop_dwell = static_cast<int>(c.getInt("stop_dwell"));
  p.max_range = c.getDouble("max_range");
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
      << p.ego_turn_noise << " x yaw rate x range, dynamic > " << p.dynamic_speed << " m/s, static < "
      << p.static_speed << " m/s, dwell " << p.stop_dwell << " frames";
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

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MotionBevTracker>(
    {"motion_bev_tracker", "BEV motion tracker",
     "Tracks boxes in the world BEV (Kalman + Hungarian) and marks them static, dynamic or unknown",
     {1, 0, 0}, kFields}))
