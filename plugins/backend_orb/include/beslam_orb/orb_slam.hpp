// beslam::orb::OrbSlam: an ORB-SLAM2-class monocular SLAM core (tracking + local mapping + relocalisation,
// no loop closure).
//
// One call per frame: track(grey image, optional label mask, timestamp, frame index). Poses are
// T_world_cam (camera-to-world). The world is the first keyframe's camera frame, scaled so the median
// scene depth at initialisation is 1.
//
// Label mask (CV_16UC1, same size as the image, or empty): 0 = background, 1 = dynamic object (no
// features), >= 1000 = static object 1000 + id (lower FAST threshold, a reserved share of the budget,
// map points made there are "trusted": never culled as recent points, weighted by
// Options::static_object_weight in pose optimisation and bundle adjustment; 1.0 by default).
//
// Map reuse: loadMap() / saveMap() (or Options::load_map / save_map) and Options::localisation_only.
//
// Threading: with Options::threaded_mapping the local mapping of a new keyframe runs on its own thread
// while the caller goes on (and while the next frame's features are extracted); tracking of the next
// frame waits for it. Results are the same as in the default single-threaded mode. With
// Options::concurrent_mapping tracking does not wait for a keyframe's mapping (ORB-SLAM2's model): faster,
// but results depend on thread timing.
// With a mapping thread, addObjectLandmarks() and dropObject() return at once: their changes are applied in
// call order once mapping is idle (before the next frame is tracked, or by any accessor), the same order
// against mapping as inline, so they change no result.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace beslam::orb {

// Pinhole intrinsics of rectified images (no distortion).
struct Camera {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

// Object landmarks (addObjectLandmarks) in the optimisation: Off stores them only; BA adds an object-pose node
// per landmark with camera-object and map-point-on-surface factors to local BA (docs/object-ba.md).
enum class ObjectLandmarkMode { Off, BA };
// How parked cars' metric boxes hold a metric map's scale in local BA (docs/metric-scale.md): one anchor
// per car measured by its box centres (unbiased), or a range prior per keypoint where its ray enters the
// box (biased short by how a car fills its box; kept for ablations).
enum class ObjectScaleHold { Anchors, Ranges };
// A bundle adjustment's solver (src/optimize/schur_lm.hpp): our Schur-complement LM on both cores, or Ceres.
enum class BundleAdjustmentSolver { Schur, Ceres };

// ORB extraction (features/orb_extractor.hpp): the pyramid, the FAST thresholds and the share of the
// budget that static objects (mask label >= 1000) may take.
struct ExtractorOptions {
  int features = 2000;                      // keypoints per frame
  double scale_factor = 1.2;                // pyramid scale step
  int levels = 8;                           // pyramid levels
  int fast_initial = 20;                    // FAST threshold per cell
  int fast_fallback = 7;                    // FAST threshold of a cell that found nothing
  int static_object_fast = 7;               // FAST threshold on static objects (label >= 1000)
  double static_object_budget_share = 0.3;  // share of each level's budget reserved for static objects
  int cell_size = 30;                       // FAST cell (px)
  int border = 19;                          // keypoints keep this far from every level's border
};

// Every tunable with its default. validate() names the first violated constraint.
struct Options {
  // Features (features/).
  ExtractorOptions extractor;
  int init_features_factor = 2;       // x extractor.features while initialising
  double static_object_weight = 1.0;  // information multiplier of trusted (static object) points
  // Matching / tracking.
  double fps = 10.0;                 // frame rate: max frames between keyframes
  int min_tracked_inliers = 30;      // local-map inliers for tracking to be OK
  double keyframe_ref_ratio = 0.9;   // new keyframe when tracking < ratio x reference's points
  double keyframe_floor_ratio = 2;   // ... or when tracking < this x min_tracked_inliers (0: the ratio alone)
  int keyframe_min_gap = 2;          // frames between keyframes at least (ORB-SLAM's "mapper busy")
  int lost_reset_max_keyframes = 5;  // lost with at most this many keyframes -> reset and re-init
  // Place recognition (docs/place-recognition.md). vocabulary: a file written by `beslam vocab train`
  // ("" = none: no bag of words; tracking falls back to projection searches).
  std::string vocabulary;
  // Reference-keyframe tracking by bag of words (ORB-SLAM2) instead of the wide projection search: off,
  // it did not help (KITTI 06 median APE 0.045 m against 0.037 m; docs/place-recognition.md).
  bool bow_matching = false;
  bool relocalisation =
      true;  // when lost: BoW candidates + PnP (with a vocabulary), else a search around the last pose
  // On a metric map, a BoW candidate's pose is refused when the parked cars its keyframe sees, placed by
  // that pose, mostly have no car box of the frame near them (objects/object_layout.hpp).
  bool relocalisation_object_check = true;
  // Loop closing (loop/loop_closer.hpp; needs a vocabulary): detection, Sim3 (SE3 once metric), essential
  // graph and global BA. loop_object_check: BE-SLAM's BEV check, parked cars must agree after the loop.
  // Until a loop is closed the tracker's local map keeps to the last loop_own_stretch_keyframes keyframes
  // (0: every covisible keyframe, as ORB-SLAM2), so that tracking does not join a lap's two ends through
  // points seen far ahead before the loop closer can (docs/place-recognition.md, "Loop closing").
  bool loop_closure = true;
  bool loop_object_check = true;
  int loop_own_stretch_keyframes = 30;
  int loop_global_ba_iterations = 10;  // 0: none after the essential graph
  // The global BA keeps local BA's parked-car terms on a metric map: one anchor per parked car on its
  // keyframes' boxes and, with object_landmarks: ba, the object landmarks (the LiDAR ranges it keeps always).
  bool loop_global_ba_objects = true;
  // schur: SchurLevenbergMarquardt, block-sparse past 60 keyframes (the same steps as Ceres, on both
  // cores); ceres: Ceres' SPARSE_SCHUR LM, as before.
  BundleAdjustmentSolver loop_global_ba_solver = BundleAdjustmentSolver::Schur;
  // Local mapping.
  int triangulation_neighbours = 20;  // covisible keyframes to triangulate with
  // Epipolar matching for new points as ORB-SLAM2 does it: best under the strict threshold, no ratio
  // test (1.0), no rotation check. Measured over 4 seeds: KITTI 00 APE 0.98 m mean (ratio 0.8 with the
  // rotation check: 1.12 m), KITTI 06 0.040 m (0.022 m).
  double triangulation_ratio = 1.0;                // nearest-neighbour ratio along the epipolar line (1 = off)
  double triangulation_max_cos_parallax = 0.9998;  // new points need more parallax than this (cosine)
  bool triangulation_check_orientation = false;    // rotation-consistency histogram on epipolar matches
  bool triangulation_bow = false;  // epipolar candidates only under the same BoW node (ORB-SLAM2; needs a vocabulary)
  int local_ba_iterations_robust = 5;   // Huber round
  int local_ba_iterations_refine = 10;  // round without robust loss, outliers removed
  int local_ba_max_keyframes = 0;       // 0 = all covisible keyframes move
  // schur: SchurLevenbergMarquardt (deterministic on any thread count; dense up to 60 moving keyframes,
  // block-sparse past that; with object landmarks Ceres); ceres: Ceres' Schur LM, as before issue 19.
  BundleAdjustmentSolver local_ba_solver = BundleAdjustmentSolver::Schur;
  bool keyframe_culling = true;
  // Ground-height prior (beyond ORB-SLAM2; for a camera on a vehicle over a road): local BA holds the
  // camera's height above the plane fitted to each keyframe's low points at the height seen over the
  // first keyframes, which ties the monocular scale along the run to its start. Off by default.
  bool ground_prior = false;
  double ground_prior_sigma = 0.2;     // std-dev of one ground point's height, share of the height
  int ground_reference_keyframes = 5;  // keyframes whose median camera height is the reference
  int ground_min_inliers = 25;         // a keyframe's ground plane needs this many points
  int ground_pool_keyframes = 5;       // its fit also takes the road points of covisible keyframes this close
  // Metric scale (beyond ORB-SLAM2; docs/metric-scale.md): once the ground planes of the first keyframes
  // agree, the map is rescaled so the camera sits camera_height metres over them, and the ground prior
  // (switched on with it) holds that height: poses and points are in metres from then on.
  bool metric_scale = false;
  bool report_map_moves = true;    // tell the host how local BA moved the map under the last camera
  double camera_height = 0;        // the rig's camera height over the road, metres
  double metric_max_spread = 0.1;  // the reference fits' heights must agree this well (rel. MAD)
  // Once metric: the last ground_reference_keyframes fits that say the camera height is off by more than
  // this share (and more than twice their standard error) scale the map back from the oldest of them on.
  double metric_correction_min = 0.02;  // 0: no correction, the ground prior alone holds the scale
  // Static objects' boxes as a metric source (ObjectBox), and how they hold the scale once metric; the
  // std-dev of a box's range (anchors: of its centre), metres and per metre.
  bool object_scale = true;
  ObjectScaleHold object_scale_hold = ObjectScaleHold::Anchors;
  double object_range_sigma = 0.15;
  double object_range_sigma_per_m = 0.02;
  // LiDAR ranges as a metric source (scale/lidar_range.hpp), where frames carry a scan: once
  // lidar_reference_keyframes keyframes each measure the map's unit from their keypoints' LiDAR ranges (at
  // least lidar_min_points each) and agree within metric_max_spread, the map is rescaled; from then on each
  // keypoint's LiDAR range holds its map point in local BA with this std-dev (metres, plus per metre), and
  // neither the road fits nor the parked cars' boxes rescale it.
  bool lidar_scale = true;
  int lidar_reference_keyframes = 2;
  int lidar_min_points = 20;
  double lidar_range_sigma = 0.05;
  double lidar_range_sigma_per_m = 0.005;
  // Once the scan holds the scale, ORB-SLAM2's stereo / RGB-D rules: after triangulation, local mapping makes
  // map points of a keyframe's keypoints that have a LiDAR range and still no point (the nearest
  // lidar_points_per_keyframe, ORB-SLAM2's 100 nearest), and a frame that tracks fewer than 100 of its
  // ranged keypoints while more than 70 are untracked asks for a keyframe (thin stretches get points in time).
  bool lidar_points = true;
  int lidar_points_per_keyframe = 100;
  // Object landmarks in local BA (objects/object_factors.hpp, docs/object-ba.md). Off by default: a gain is
  // shown only with LiDAR-fitted cars on dynamic_street.
  ObjectLandmarkMode object_landmarks = ObjectLandmarkMode::Off;
  double object_pose_weight = 1.0;       // information multiplier of the camera-object (box) factors
  double object_surface_weight = 1.0;    // information multiplier of the map-point-on-surface factors
  double object_box_sigma = 0.15;        // box centre std-dev (m) (the anchors' object_range_sigma) ...
  double object_box_sigma_per_m = 0.02;  // ... plus this per metre of range
  double object_yaw_sigma_deg = 10.0;    // box heading std-dev
  double object_surface_sigma = 0.1;     // map point to nearest surface sample std-dev (m)
  double object_surface_gate = 0.5;      // points farther than this (m) from every sample get no factor
  bool threaded_mapping = false;
  // Local mapping on its own thread while tracking goes on (ORB-SLAM2's model, src/mapping/map_gate.hpp):
  // tracking waits only for the mapper's current step, no keyframe is made while mapping is busy, a local
  // BA is cut short when tracking wants one. Faster on two cores, not reproducible (results depend on
  // thread timing; docs/performance.md). Implies threaded_mapping.
  bool concurrent_mapping = false;
  // Initialisation.
  int ransac_iterations = 200;
  double init_min_parallax_deg = 1.0;  // two-view reconstruction needs this much parallax
  int init_match_max_level = 0;        // initial matching uses keypoints up to this pyramid level
  uint64_t seed = 42;                  // seeds every random choice (RANSAC)
  // Map reuse (src/map_io/map_file.hpp: versioned binary file, atomic save). load_map: a map file the
  // constructor loads (the camera and the pyramid options must be the ones it was made with); tracking
  // then starts by localising in it. save_map: the file finish() saves the map to. localisation_only:
  // track against the loaded map without changing it (no keyframes, map points, culling, bundle
  // adjustment, rescaling or map statistics); without a loaded map nothing is tracked.
  std::string load_map, save_map;
  bool localisation_only = false;

  bool validate(std::string* error) const;
};

enum class TrackingState { NotInitialized, Ok, Lost };

// A metric 3D box of a tracked car in the frame being tracked (camera frame). Every car's centre over time
// feeds the parked-car scale estimate (scale/parked_car_scale.hpp) before the map is metric; keypoints on
// the mask label 1000 + object_id of a parked one get the metric range at which their ray enters its box:
// a scale source too, and a range prior in local BA once metric (docs/metric-scale.md).
struct ObjectBox {
  int32_t object_id = -1;                                       // track id (mask label 1000 + id)
  bool parked = false;                                          // called static: its keypoints get ranges
  Eigen::Isometry3d T_cam_box = Eigen::Isometry3d::Identity();  // box centre; axes along length, height, width
  Eigen::Vector3d size = Eigen::Vector3d::Zero();               // extent along the box's x, y, z axes
};

struct TrackResult {
  TrackingState state = TrackingState::NotInitialized;
  bool is_keyframe = false;
  int64_t keyframe_id = -1;                                       // when is_keyframe
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // valid when state == Ok
  int tracked_points = 0;                                         // pose inliers
  bool world_is_metric = false;                                   // T_world_cam (and the map) in metres
  int features = 0, features_static = 0;                          // keypoints; on static-object labels
  int features_lidar = 0;                                         // keypoints with a LiDAR range
  int lidar_points = 0;    // map points made from keyframes' LiDAR ranges since the last frame (Options::lidar_points)
  int tracked_static = 0;  // inliers on static-object map points
  std::vector<std::pair<std::string, double>> stage_ms;  // extract, track, local_map, mapping...
  bool relocalised = false;                              // this frame recovered from Lost
  bool loop_closed = false;      // a loop was closed before this frame was tracked (the map moved)
  double loop_correction_m = 0;  // then: how far the loop keyframe's centre moved
  // The metric world moved before this frame was tracked (a loop correction, a change of scale, and with
  // report_map_moves local BA under the last frame's reference keyframe): a point the world held at p is at
  // world_change_scale * (R * p) + t now, [R | t] = *S_new_old, exact about the last tracked camera. Empty
  // when nothing moved it, or the world was not metric before.
  std::optional<Eigen::Isometry3d> S_new_old;
  double world_change_scale = 1.0;
  int loop_object_rejections = 0;            // loop candidates the BEV object check refused since the last frame
  int relocalisation_object_rejections = 0;  // relocalisation candidates the parked-car check refused
  int object_landmarks = 0;                  // object landmarks in the map
  int object_factors = 0;                    // object factors (box and surface) in the last local BA before this frame
  // The frame's keypoints: pixel, mask label under it, matched to a map point (pose inlier), octave.
  struct Keypoint {
    float x = 0, y = 0;
    uint16_t label = 0;
    bool matched = false;
    uint8_t octave = 0;
  };
  std::vector<Keypoint> keypoints;
  // When is_keyframe: the map points the new keyframe observes (for a reconstructor): those it matched,
  // and the static-object points in its view (labelled by their object).
  struct ObservedPoint {
    int64_t id = -1;
    Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
    float x = 0, y = 0;  // pixel of the keypoint it was matched at
    uint16_t label = 0;  // mask label under it
    int observations = 0;
  };
  std::vector<ObservedPoint> keyframe_points;
};

struct FramePose {
  int64_t frame_index = 0;
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

// A map point as exported (PLY output): position, colour, observation count.
struct CloudPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  uint8_t grey = 0;
  uint8_t r = 0, g = 0, b = 0;
  int observations = 0;
  bool on_static_object = false;
};

// An object reconstructed by another module (a parked car), in world coordinates.
struct ObjectLandmark {
  int64_t id = 0;           // label value on the mask is 1000 + id
  double confidence = 1.0;  // the reconstruction's, in (0, 1]: scales the information of its factors
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  // body x forward, y left, z up; box centre
  Eigen::Vector3d dimensions = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> points_object;  // surface samples in the object frame
};

struct Statistics {
  int frames = 0, frames_tracked = 0, keyframes = 0, keyframes_culled = 0, map_points = 0;
  int resets = 0, relocalisations = 0;
  int loop_closures = 0, loop_object_rejections = 0, loop_candidates = 0;
  int relocalisation_object_rejections = 0;
  std::vector<std::pair<int64_t, int64_t>> loop_frames;  // (frame, matched earlier frame) per closure
  int64_t initialised_at_frame = -1;
  int64_t metric_from_frame = -1;   // first frame tracked in metres (-1: never)
  double metric_scale_factor = 0;   // the factor the map was multiplied by then
  int object_points_dropped = 0;    // map points of static objects that started to move
  int scale_corrections = 0;        // local scale corrections from the ground fits
  int64_t object_scale_frame = -1;  // frame at which the parked cars' boxes set the scale (-1: never)
  double object_scale_factor = 0;   // the factor they applied
  int object_scale_tracks = 0;      // cars in the agreeing cluster
  bool lidar_scaled = false;        // the LiDAR ranges set the scale (metric_from_frame) and hold it
  int lidar_points = 0;             // map points made from keyframes' LiDAR ranges (Options::lidar_points)
};

class OrbSlam {
 public:
  // Throws std::invalid_argument on bad input, std::runtime_error when Options::load_map cannot be loaded.
  OrbSlam(const Camera& camera, const Options& options);
  ~OrbSlam();
  OrbSlam(const OrbSlam&) = delete;
  OrbSlam& operator=(const OrbSlam&) = delete;

  // Constant-velocity prediction of the next frame's pose (empty until tracking has a velocity). The
  // velocity is per frame (frames assumed evenly spaced); the timestamp is not used.
  std::optional<Eigen::Isometry3d> predictPose(double timestamp) const;

  // A frame's mask-independent extraction work (grey image, pyramids, FAST corners), done ahead of its
  // track() with the same image: safe to call from another thread while the other calls run. track()
  // returns the same with or without it.
  void prepare(const cv::Mat& gray, int64_t frame_index);

  // gray: CV_8UC1 (or CV_8UC3 BGR, converted; colour kept for map points); label_mask: CV_16UC1 or empty;
  // car_boxes: the frame's cars (ObjectBox; object_id -1 for untracked ones, which only relocalisation's
  // parked-car check uses), used with metric_scale. lidar_cam: the frame's LiDAR
  // scan in the camera frame (metres), if it has one; used with metric_scale and lidar_scale.
  TrackResult track(const cv::Mat& gray, const cv::Mat& label_mask, double timestamp, int64_t frame_index,
                    const std::vector<ObjectBox>& car_boxes = {}, const Eigen::Matrix3Xf* lidar_cam = nullptr);

  // Waits for the mapping thread and runs a last local bundle adjustment (not in localisation-only mode),
  // then saves the map to Options::save_map if set (throws std::runtime_error naming the file on failure).
  void finish();

  // Saves the map (live keyframes, map points, covisibility, object landmarks, camera) to `path`
  // atomically; throws std::runtime_error naming the file. Waits for the mapping thread.
  void saveMap(const std::string& path) const;
  // Loads a map file into this OrbSlam before its first track(); throws std::runtime_error naming the
  // file and the problem (another format version or camera, truncated, corrupt) and keeps no part of it.
  void loadMap(const std::string& path);

  // Each tracked frame: its pose relative to its reference keyframe composed with that keyframe's
  // current (optimised) pose. Untracked frames are absent.
  std::vector<FramePose> trajectory() const;
  // Each tracked frame's pose as tracking estimated it at the time.
  std::vector<FramePose> onlineTrajectory() const;
  std::vector<FramePose> keyframes() const;
  std::vector<CloudPoint> mapPoints() const;

  // Landmarks from a reconstructor: kept (same id replaces) and returned by objectLandmarks() (their poses as
  // local BA refined them). With Options::object_landmarks = BA they enter local BA (docs/object-ba.md);
  // off, they are only stored. Trust comes from the mask: features on label 1000 + id.
  void addObjectLandmarks(const std::vector<ObjectLandmark>& landmarks);
  std::vector<ObjectLandmark> objectLandmarks() const;

  // Object `object_id` (mask label 1000 + id) started to move: its map points and its landmark leave the map.
  void dropObject(int32_t object_id);

  Statistics statistics() const;
  const Options& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace beslam::orb
