// The motion checker's core: tracks 3D boxes in the world frame's bird's-eye view and decides, per
// object and frame, whether it is static (parked), dynamic or unknown. Plain C++ over the ABI's box
// struct, so the plugin, the tests and the benchmarks share one implementation.
//
// Frames. Boxes arrive in the camera frame (x right, y down, z forward; geometric centre). They are
// moved into the world frame with T_world_cam and projected onto the world's x-z plane: the world is
// assumed to be a camera-style frame with y pointing (roughly) down, as every backend's map frame is
// (the first camera). Range is the box centre's horizontal distance from the camera.
//
// Per frame: predict every track with a constant-velocity Kalman filter [x z vx vz]; build a cost
// matrix (BEV centre distance, gated by a range-dependent radius, or 1 - BEV IoU of the rotated
// footprints); solve it globally (Hungarian); update matched tracks, start tracks for the rest, and
// drop tracks missed for longer than max_miss_time. Tracks keep predicting through short occlusions.
//
// Motion decision. Each track fits a straight line (least squares) to its world positions over the
// last window_dynamic / window_static seconds and gets a speed and its standard error from the noise
// model sigma(r) = pos_sigma + pos_sigma_per_m * r (depth and bearing errors grow with range; the
// residual spread is used when larger, and a window whose residual exceeds max_residual times the model
// gives no evidence: the track jumped between objects). A detector velocity (absolute velocity over ground, in camera
// axes) is fused by inverse variance. Evidence per frame:
//   dynamic: speed - z_dynamic * sigma_v > dynamic_speed   (short window; rejects "parked")
//   static:  speed + z_static * sigma_v < static_speed     (long window; rejects "moving")
// sigma_v also holds the ego-motion error, ego_speed_noise * v_ego + ego_turn_noise * yaw_rate_ego * r (the
// pose source's drift: a heading-rate error moves a far object sideways), which more positions do not
// average away; the detection noise does, so a track seen longer gets a smaller sigma_v.
// A static track also has dynamic evidence when its latest positions (mean of 3) leave its parked
// position (a running mean while static) by displacement_margin plus z_dynamic standard errors.
// Hysteresis: UNKNOWN -> STATIC on the first static evidence, UNKNOWN -> DYNAMIC after start_frames
// dynamic frames, STATIC -> DYNAMIC after pull_out_frames (a car known parked asks for more: its box
// jumping is likelier than its pulling out), DYNAMIC -> STATIC after stop_dwell static frames; a run is
// broken only by contrary evidence (frames with none neither add nor break). Far objects whose speed
// cannot be pinned down stay UNKNOWN (the paper checks nearby cars first). Without any camera pose the
// tracker still tracks (camera frame) but reports UNKNOWN.
//
// Boxes with their own noise (ABI 1.5, BESLAM_BOX_HAS_POSITION_SIGMA: a ground-lifted monocular box knows its
// bearing far better than its range): each position gets a covariance, range noise along the line of sight
// and bearing noise across it (each at least the model's sigma(r)), which the Kalman update, the gate (the
// distance along the line of sight counts in units of the noise across it) and a generalised least-squares
// line fit use. The box's range drift (a range error that changes with the range, e.g. a road pitch error)
// adds (range_drift * closing speed)^2 along the line of sight to the velocity's covariance. Static evidence
// then needs the speed bound in every direction, or, since traffic moves along the road and the road runs
// along the ego's travel, both the speed along that direction (velocity constrained to it) and the velocity
// across it (unconstrained) below static_speed. Windows whose boxes carry no noise take the plain fit above,
// unchanged.
//
// No pose for a frame (the backend lost): the last two poses are carried on for at most max_miss_time. Boxes
// placed with that guess (and, with uncertain_evidence off, boxes their detector flags uncertain) keep their
// tracks alive and take their state, but give no evidence and start no track; an uncertain box that matches no
// track in the BEV takes the track whose image box of the frame before overlaps its own most (IoU >= 0.3);
// pose jitter is measured between consecutive given poses only. A world change (worldMoved: a loop correction)
// re-expresses every track in the new world.
//
// Pose jitter (pose_jitter: true, for the poses of a monocular SLAM backend): a vehicle cannot leave its
// constant-velocity path by much between two frames, so how far the given poses do (a backend correcting
// itself) is measured as an RMS over the last window_static seconds, and every world position made with
// them carries it as extra position noise. Ground truth and stereo odometry have almost none. Until the
// poses have been watched for window_static seconds their jitter is unknown and no track is decided.
//
// A young map (for a monocular SLAM backend; both off by default). Its unit drifts by several per cent over a
// second in its first seconds, which moves every parked car along the ego's path at that share of its speed:
//  - settling_speed_noise for settling_time after the first pose (or at least a change of scale's own size
//    after the change, worldMoved with scale != 1) joins the ego-motion error of the dynamic test and the
//    pull-out test only; the static test is unchanged.
//  - reference_tracks: with at least that many other static tracks, a track's dynamic evidence is its
//    velocity against their median apparent velocity (fitted over window_dynamic before this frame), and a
//    parked track's displacement is measured net of that velocity over the time since it was parked.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "beslam/data.h"
#include "beslam/motion/parallax.hpp"

namespace beslam::motion {

struct Params {
  // Association.
  std::string association = "distance";  // "distance" (BEV centre distance) | "iou" (1 - BEV IoU)
  double gate = 2.0;                     // m: BEV distance gate at range 0
  double gate_per_m = 0.03;              // m of gate added per metre of range
  double min_iou = 0.01;                 // "iou": smallest BEV IoU accepted
  bool match_across_classes = false;     // let car/van/truck boxes match each other regardless (always on),
                                         // and any class any other when true
  // Kalman filter.
  double accel_sigma = 4.0;        // m/s^2, white-noise acceleration
  double pos_sigma = 0.1;          // m, position noise of a detection at range 0
  double pos_sigma_per_m = 0.005;  // m per metre of range
  double velocity_sigma = 1.0;     // m/s, noise of a detector's own velocity
  // Ego-motion error (the pose source's drift): a parked car seems to move at up to
  // ego_speed_noise * (ego speed) + ego_turn_noise * (ego yaw rate) * range. A velocity error that more
  // observations do not average away; it widens every speed test and the pull-out test.
  double ego_speed_noise = 0.0;      // fraction of the ego's speed (odometry translation drift)
  double ego_turn_noise = 0.05;      // fraction of the ego's yaw rate (heading-rate error; lateral, grows with range)
  double init_velocity_sigma = 5.0;  // m/s, velocity uncertainty of a new track (no detector velocity)
  bool pose_jitter = false;          // measured pose jitter adds to every position's noise (for SLAM poses)
  // Parked reference: with at least this many other static tracks in view, a track's dynamic evidence is its
  // velocity relative to their common (median) apparent velocity, which is the pose source's own error (a map
  // unit still settling moves every parked car along the ego's path at once). 0: off.
  int reference_tracks = 0;
  // A settling map unit (a monocular map just made metric: its unit drifts by several per cent over a second
  // for its first seconds): for settling_time after the first pose, a parked car may seem to move at up to
  // settling_speed_noise * (ego speed), which dynamic evidence must clear (static evidence need not: a car
  // creeping at that speed is rarer than a parked one seen through a young map). A change of scale the
  // backend reports (worldMoved with scale != 1) restarts the time, at least at the change's own size.
  double settling_speed_noise = 0;
  double settling_time = 0;  // s; 0: off
  // A box its detector flags BESLAM_BOX_UNCERTAIN (an image detector: cut by the image border, too far or
  // its range too unsure) is evidence like any other (true), or only keeps its track alive and takes its
  // state, starting no track (false: for boxes lifted from one image, whose cut boxes move with the cut).
  bool uncertain_evidence = true;
  // Track life.
  double max_miss_time = 1.0;  // s a track survives without a detection
  int max_history = 64;        // observations kept per track
  // Motion decision.
  double window_dynamic = 0.5;  // s of history for dynamic evidence
  double window_static = 1.5;   // s of history for static evidence
  int min_observations = 3;     // before any decision (without a detector velocity)
  double max_residual = 2.0;    // a window whose line-fit residual exceeds this many noise sigmas gives no evidence
  // The two classes by definition: a car slower than dynamic_speed is parked, one faster than static_speed
  // moves (KITTI's truth: 0.3 and 1 m/s). Dynamic evidence rejects "parked", static evidence rejects "moving";
  // range enters through the noise model (pos_sigma_per_m, ego_turn_noise), not through these speeds.
  double dynamic_speed = 0.3;  // m/s, dynamic evidence: speed - z_dynamic * sigma_v above this
  double static_speed = 1.0;   // m/s, static evidence: speed + z_static * sigma_v below this
  double z_dynamic = 3.0;      // standard errors the speed must clear (2D radial: 3 ~ 1 % false alarms a test)
  double z_static = 2.0;
  double displacement_margin = 0.75;  // m: a static track whose last 3 positions leave its parked position by
                                      // this plus z_dynamic standard errors has dynamic evidence
  int anchor_frames = 30;             // depth of the parked position's running mean
  int start_frames = 1;               // UNKNOWN -> DYNAMIC after this many dynamic frames in a row
  int pull_out_frames = 3;            // STATIC -> DYNAMIC after this many dynamic frames in a row
  int stop_dwell = 5;                 // DYNAMIC -> STATIC after this many static frames in a row
  double max_range = 200.0;           // m: boxes farther away get a track but stay UNKNOWN
  // Parallax evidence (parallax.hpp; for boxes lifted from one image, whose range drifts too much for the
  // speed tests to call a parked car static): a track whose triangulated near surface lies within
  // parallax_tolerance (a share) of its lifted box's nearest corner has static evidence, and a dynamic run is
  // broken by it. For window_static seconds after such a measurement the lifted boxes' speed and displacement
  // give no dynamic evidence (their range drift is what the measurement showed is not motion); a measurement
  // outside the tolerance ends that at once. The tolerance is the lifted range's own error; what passes with it besides
  // parked cars is a car moving along the ego's line of travel at less than 1 - 1 / (1 + tolerance) of the ego's speed
  // (same direction) or 1 / (1 - tolerance) - 1 (oncoming): the epipolar ambiguity.
  bool parallax = false;
  double parallax_tolerance = 0.3;
  ParallaxParams parallax_check;
  double default_dt = 0.1;  // s, when timestamps do not increase

  // Empty when valid, else the first violated constraint ("gate must be > 0").
  std::string validate() const;
};

// What the tracker decided for one box.
struct Decision {
  int32_t track_id = -1;
  int32_t motion_state = BESLAM_MOTION_UNKNOWN;
  double speed = 0;        // m/s over ground (fused estimate), 0 when unknown
  double speed_sigma = 0;  // its standard error (0 when not estimated)
  double range = 0;        // m
};

class BevTracker {
 public:
  explicit BevTracker(const Params& params = {});

  // One frame: T_world_cam from the backend, or nullopt (the tracker then extrapolates the last poses for
  // at most max_miss_time, after which every box is UNKNOWN and the tracks wait; with no pose ever it works
  // in the camera frame and answers UNKNOWN). Returns one decision per box, in order.
  // Throws std::invalid_argument on a non-finite box.
  std::vector<Decision> update(double timestamp, const std::optional<Eigen::Isometry3d>& T_world_cam,
                               const std::vector<beslam_box3d>& boxes);

  // Writes track_id and motion_state into the boxes (the motion checker's contract).
  void classify(double timestamp, const std::optional<Eigen::Isometry3d>& T_world_cam,
                std::vector<beslam_box3d>& boxes);

  // The pose source moved its world (a loop correction, a change of scale): a point it held at p_old is at
  // scale * R * p_old + t now ([R | t] = S_new_old). Every track, its history and parked position, and the
  // last poses are expressed in the new world, so the next pose (already in it) continues them: the
  // correction reads neither as motion of the cars nor as pose jitter. The camera centres move by the whole
  // change; a box's offset from the camera that saw it is metric and only turns. Throws
  // std::invalid_argument on a non-finite transform or a scale <= 0.
  void worldMoved(const Eigen::Isometry3d& S_new_old, double scale);

  // A parallax measurement for a track this frame (ParallaxCheck, after update() gave the ids): static evidence
  // when the depth ratio is within parallax_tolerance of 1, none otherwise. Returns the track's state after
  // it (nullopt for a track that no longer exists).
  std::optional<int32_t> parallaxEvidence(int32_t track_id, double depth_ratio);

  void reset();
  size_t trackCount() const { return tracks_.size(); }
  const Params& params() const { return params_; }
  // The ego's BEV speed (m/s) and yaw rate (rad/s) between the last two poses given (0 before two).
  double egoSpeed() const { return ego_speed_; }
  double egoYawRate() const { return ego_yaw_rate_; }
  double poseJitter() const { return jitter_rms_; }  // m: RMS distance of the poses from constant velocity

 private:
  struct Observation {
    double t;
    Eigen::Vector2d p;          // world BEV
    Eigen::Vector2d cam;        // world BEV centre of the camera that saw it (a world change scales from it)
    double v_sigma;             // apparent velocity from ego-motion error (m/s)
    double v_settling;          // the same from a map unit still settling: dynamic evidence only (m/s)
    Eigen::Matrix2d cov;        // position covariance in the world BEV
    Eigen::Matrix2d drift_cov;  // velocity covariance of the box's range drift while the camera closes in
    bool isotropic;             // cov == sigma^2 I and no drift (the box gave no noise of its own)
  };
  struct Track {
    int32_t id = -1;
    int32_t class_id = 0;
    Eigen::Vector4d x;  // x z vx vz
    Eigen::Matrix4d P;
    double last_t = 0;   // last detection
    double yaw_bev = 0;  // footprint heading in the BEV plane
    double length = 4, width = 1.8;
    int hits = 0;
    Eigen::Vector4d bbox2d = Eigen::Vector4d::Zero();  // the last detection's 2D box (x1 y1 x2 y2), if it had one
    double bbox2d_t = -1;                              // its time; < 0: none
    double parallax_t = -1e18;  // time of the last parallax measurement within the tolerance (cleared by one outside)
    std::deque<Observation> history;
    int32_t state = BESLAM_MOTION_UNKNOWN;
    int dynamic_run = 0, static_run = 0;
    Eigen::Vector2d anchor = Eigen::Vector2d::Zero();  // where a static track is parked
    Eigen::Matrix2d anchor_cov = Eigen::Matrix2d::Zero();
    double anchor_t = 0;                                   // mean time of the parked position's observations
    Eigen::Vector2d anchor_cam = Eigen::Vector2d::Zero();  // mean camera centre of those observations
    int anchor_n = 0;
  };
  struct Speed {
    bool valid = false;
    double speed = 0;
    double sigma = 0;        // standard error of the speed (along the fitted velocity)
    double sigma_bound = 0;  // the largest standard error in any direction
    double speed_bound = 0;  // the static test's: speed plus z_static standard errors, at most
    Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  // the fitted (fused) BEV velocity
  };
  // A static track's apparent velocity over window_dynamic, before this frame's update (reference_tracks).
  struct Reference {
    int32_t track_id;
    Eigen::Vector2d velocity;
    double sigma;
  };

  struct Fit {
    Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
    double sigma = 0, sigma_bound = 0, speed_bound = 0;  // as in Speed, the ego-motion error included
    bool consistent = true;                              // the residuals are within max_residual of the noise
  };
  // One frame's boxes in the world BEV, with their noise (update's stages below).
  struct Placed {
    std::vector<Eigen::Vector2d> p;                   // world BEV centre
    std::vector<double> range, v_sigma, yaw;          // m from the camera; ego-motion velocity error; BEV heading
    double v_settling = 0;                            // a settling map unit's velocity error (dynamic tests only)
    std::vector<Eigen::Matrix2d> cov, drift_cov;      // position covariance; range-drift velocity covariance
    std::vector<Eigen::Vector2d> line_of_sight;       // unit BEV bearing; zero: isotropic noise
    std::vector<std::optional<Eigen::Vector2d>> vel;  // the detector's own velocity, world BEV
  };
  // update's stages, in order. advanceTime: the frame's time (dt in: the default step, out: the step taken).
  double advanceTime(double timestamp, double& dt);
  // The frame's pose (given, or the last two carried on); false when no pose has come for longer than a track
  // may coast (every box is then unknown). Measures the pose jitter and the ego's motion.
  bool takePose(double now, const std::optional<Eigen::Isometry3d>& T_world_cam_in,
                std::optional<Eigen::Isometry3d>& T_world_cam, bool& extrapolated);
  void predict(double dt);  // every track's constant-velocity prediction over dt
  Placed place(const std::vector<beslam_box3d>& boxes, const Eigen::Isometry3d& T_wc, double now) const;
  // Box i's track index, or -1: gated costs, one global assignment.
  std::vector<int> associate(const std::vector<beslam_box3d>& boxes, const Placed& placed) const;
  // An uncertain box's track by its image box (the one of the frame before overlapping most), or -1.
  int matchByImageBox(const beslam_box3d& b, const std::vector<char>& matched, double now, double dt) const;
  // Tracks of the first old_count that were not matched and are missed too long go.
  void dropMissed(size_t old_count, const std::vector<char>& matched, double now, double dt);

  // The line fit when some position of the window has its own (range, bearing) noise; nullopt when the
  // window spans no time.
  std::optional<Fit> fitSpeedAnisotropic(const std::deque<Observation>& history, size_t first, bool dynamic_test) const;
  // dynamic_test: the settling unit's error counts too (v_settling).
  Speed fitSpeed(const Track& track, double window, const std::optional<Eigen::Vector2d>& det_velocity,
                 double det_sigma, bool dynamic_test) const;
  void decide(Track& track, const std::optional<Eigen::Vector2d>& det_velocity, Decision& out);
  // The parked tracks' common apparent velocity and its standard error, the given track left out; nullopt
  // when fewer than reference_tracks remain.
  std::optional<std::pair<Eigen::Vector2d, double>> parkedReference(int32_t track_id) const;
  // The last pose carried on to `now` at the last two poses' velocity and turn rate (the last pose alone
  // when there is one, or no time between them). Needs a pose.
  Eigen::Isometry3d steadyPose(double now) const;

  Params params_;
  std::vector<Track> tracks_;
  int32_t next_id_ = 0;
  bool have_time_ = false;
  double last_time_ = 0;
  bool pose_mode_ = false;                                   // tracks live in a world frame (some pose seen)
  std::vector<std::pair<double, Eigen::Isometry3d>> poses_;  // last two known poses, for extrapolation
  std::deque<std::pair<double, double>> jitter_;  // (time, squared BEV distance of a pose from its prediction)
  double jitter_rms_ = 0;                         // m, over the last window_static seconds
  std::vector<Reference> references_;             // this frame's parked tracks (reference_tracks)
  bool last_frame_posed_ = false;                 // the previous frame had a given pose (not extrapolated, not none)
  double first_pose_t_ = 0;  // time of the first pose: with pose_jitter, decisions wait window_static from it
  double scale_change_t_ = 0, scale_change_ = 0;  // the last change of scale worldMoved was told (|scale - 1|)
  double ego_speed_ = 0, ego_yaw_rate_ = 0;       // between the last two known poses (m/s, rad/s)
  Eigen::Vector2d ego_velocity_ = Eigen::Vector2d::Zero();  // BEV, between the last two known poses (m/s)
};

// BEV footprint helpers (x-z plane of the frame the box is expressed in).
double bevYaw(const Eigen::Matrix3d& R_world_cam, double yaw_cam);
// IoU of two rotated rectangles (centre, heading angle atan2(dz, dx), length, width).
double rotatedRectIoU(const Eigen::Vector2d& c1, double yaw1, double l1, double w1, const Eigen::Vector2d& c2,
                      double yaw2, double l2, double w2);

}  // namespace beslam::motion
