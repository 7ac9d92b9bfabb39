// beslam::orb options: the plugin's ground floor. Every tunable of OrbSlam with its one default, grouped
// by the module that reads it (extraction, tracking, initialisation, local mapping, loop closing, metric
// scale, object landmarks, threading, map reuse); Options aggregates them and validate() checks them.
// plugins/backend_orb/settings.json binds each user-facing setting (`backend.<name>`) to one field here
// and repeats its default for the schema; test/options_test.cpp checks that both defaults agree.
// Also the camera intrinsics (Camera) and the option enums, which most internal headers need. Includes
// no other header of the plugin. Frames in names: T_a_b maps b's coordinates into a's.
#pragma once

#include <cstdint>
#include <string>

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

// Tracking (tracking/tracker.hpp): keyframe decisions, loss and relocalisation.
struct TrackingOptions {
  double fps = 10.0;                 // frame rate: max frames between keyframes
  int min_tracked_inliers = 30;      // local-map inliers for tracking to be OK
  double keyframe_ref_ratio = 0.9;   // new keyframe when tracking < ratio x reference's points
  double keyframe_floor_ratio = 2;   // ... or when tracking < this x min_tracked_inliers (0: the ratio alone)
  int keyframe_min_gap = 2;          // frames between keyframes at least (ORB-SLAM's "mapper busy")
  int lost_reset_max_keyframes = 5;  // lost with at most this many keyframes -> reset and re-init
  // Reference-keyframe tracking by bag of words (ORB-SLAM2) instead of the wide projection search: off,
  // it did not help (KITTI 06 median APE 0.045 m against 0.037 m; docs/place-recognition.md).
  bool bow_matching = false;
  // When lost: BoW candidates + PnP (with a vocabulary), else a search around the last pose.
  bool relocalisation = true;
  // On a metric map, a BoW candidate's pose is refused when the parked cars its keyframe sees, placed by
  // that pose, mostly have no car box of the frame near them (objects/object_layout.hpp).
  bool relocalisation_object_check = true;
};

// Map initialisation (init/two_view.hpp, run by the tracker).
struct InitOptions {
  int features_factor = 2;  // x extractor.features while initialising
  int ransac_iterations = 200;
  double min_parallax_deg = 1.0;  // two-view reconstruction needs this much parallax
  int match_max_level = 0;        // initial matching uses keypoints up to this pyramid level
};

// Local mapping (mapping/local_mapper.hpp): triangulation, local bundle adjustment, keyframe culling.
struct MappingOptions {
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
};

// Loop closing (loop/loop_closer.hpp; needs a vocabulary): detection, Sim3 (SE3 once metric), essential
// graph and global BA. object_check: BE-SLAM's BEV check, parked cars must agree after the loop.
// Until a loop is closed the tracker's local map keeps to the last own_stretch_keyframes keyframes
// (0: every covisible keyframe, as ORB-SLAM2), so that tracking does not join a lap's two ends through
// points seen far ahead before the loop closer can (docs/place-recognition.md, "Loop closing").
struct LoopClosureOptions {
  bool enabled = true;
  bool object_check = true;
  int own_stretch_keyframes = 30;
  int global_ba_iterations = 10;  // 0: none after the essential graph
  // The global BA keeps local BA's parked-car terms on a metric map: one anchor per parked car on its
  // keyframes' boxes and, with object landmarks in BA, the object landmarks (the LiDAR ranges it keeps always).
  bool global_ba_objects = true;
  // schur: SchurLevenbergMarquardt, block-sparse past 60 keyframes (the same steps as Ceres, on both
  // cores); ceres: Ceres' SPARSE_SCHUR LM, as before.
  BundleAdjustmentSolver global_ba_solver = BundleAdjustmentSolver::Schur;
};

// The map's scale (read by local mapping and the facade; docs/metric-scale.md): the ground-height prior,
// metric scale from the camera height, and the parked cars' boxes and LiDAR ranges as metric sources.
struct ScaleOptions {
  // Ground-height prior (beyond ORB-SLAM2; for a camera on a vehicle over a road): local BA holds the
  // camera's height above the plane fitted to each keyframe's low points at the height seen over the
  // first keyframes, which ties the monocular scale along the run to its start. Off by default.
  bool ground_prior = false;
  double ground_prior_sigma = 0.2;     // std-dev of one ground point's height, share of the height
  int ground_reference_keyframes = 5;  // keyframes whose median camera height is the reference
  int ground_min_inliers = 25;         // a keyframe's ground plane needs this many points
  int ground_pool_keyframes = 5;       // its fit also takes the road points of covisible keyframes this close
  // Metric scale (beyond ORB-SLAM2): once the ground planes of the first keyframes agree, the map is
  // rescaled so the camera sits camera_height metres over them, and the ground prior (switched on with
  // it) holds that height: poses and points are in metres from then on.
  bool metric_scale = false;
  double camera_height = 0;        // the rig's camera height over the road, metres (the dataset's, not a setting)
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
  int lidar_reference_keyframes = 2;       // keyframes whose scale measurements must agree
  int lidar_min_points = 20;               // ranged map points a keyframe needs to measure the scale
  double lidar_range_sigma = 0.05;         // m
  double lidar_range_sigma_per_m = 0.005;  // m per m of range
  // Once the scan holds the scale, ORB-SLAM2's stereo / RGB-D rules: after triangulation, local mapping makes
  // map points of a keyframe's keypoints that have a LiDAR range and still no point (the nearest
  // lidar_points_per_keyframe, ORB-SLAM2's 100 nearest), and a frame that tracks fewer than 100 of its
  // ranged keypoints while more than 70 are untracked asks for a keyframe (thin stretches get points in time).
  bool lidar_points = true;
  int lidar_points_per_keyframe = 100;
};

// Object landmarks in local BA (objects/object_factors.hpp, docs/object-ba.md). Off by default: a gain is
// shown only with LiDAR-fitted cars on dynamic_street.
struct ObjectLandmarkOptions {
  ObjectLandmarkMode mode = ObjectLandmarkMode::Off;
  double pose_weight = 1.0;       // information multiplier of the camera-object (box) factors
  double surface_weight = 1.0;    // information multiplier of the map-point-on-surface factors
  double box_sigma = 0.15;        // box centre std-dev (m) (the anchors' ScaleOptions::object_range_sigma) ...
  double box_sigma_per_m = 0.02;  // ... plus this per metre of range
  double yaw_sigma_deg = 10.0;    // box heading std-dev
  double surface_sigma = 0.1;     // map point to nearest surface sample std-dev (m)
  double surface_gate = 0.5;      // points farther than this (m) from every sample get no factor
};

// Where local mapping runs (mapping/mapping_thread.hpp).
struct ThreadingOptions {
  // Local mapping of a new keyframe on its own thread while the caller goes on; tracking of the next frame
  // waits for it: the same results as inline.
  bool threaded_mapping = false;
  // Local mapping on its own thread while tracking goes on (ORB-SLAM2's model, src/mapping/map_gate.hpp):
  // tracking waits only for the mapper's current step, no keyframe is made while mapping is busy, a local
  // BA is cut short when tracking wants one. Faster on two cores, not reproducible (results depend on
  // thread timing; docs/performance.md). Implies threaded_mapping.
  bool concurrent_mapping = false;
};

// Map reuse (src/map_io/map_file.hpp: versioned binary file, atomic save). load_map: a map file the
// constructor loads (the camera and the pyramid options must be the ones it was made with); tracking
// then starts by localising in it. save_map: the file finish() saves the map to. localisation_only:
// track against the loaded map without changing it (no keyframes, map points, culling, bundle
// adjustment, rescaling or map statistics); without a loaded map nothing is tracked.
struct MapReuseOptions {
  std::string load_map, save_map;
  bool localisation_only = false;
};

// Every tunable with its default, by module. validate() names the first violated constraint.
struct Options {
  ExtractorOptions extractor;
  TrackingOptions tracking;
  InitOptions init;
  MappingOptions mapping;
  LoopClosureOptions loop;
  ScaleOptions scale;
  ObjectLandmarkOptions object_landmarks;
  ThreadingOptions threading;
  MapReuseOptions map_reuse;
  // Run-wide values more than one module reads.
  // Place recognition (docs/place-recognition.md): a file written by `beslam vocab train` ("" = none: no
  // bag of words, no loop closing; tracking falls back to projection searches).
  std::string vocabulary;
  double static_object_weight = 1.0;  // information multiplier of trusted (static object) points
  uint64_t seed = 42;                 // seeds every random choice (RANSAC)
  // Once metric: tell the host how local BA moved the map under the last camera (TrackResult::S_new_old).
  bool report_map_moves = true;

  bool validate(std::string* error) const;
};

}  // namespace beslam::orb
