// Bundle adjustment with Ceres over keyframe poses and map points.
// Local BA: the new keyframe and its covisible keyframes move, keyframes that see the same points but
// are not covisible stay fixed; a robust (Huber) round, outliers dropped, a refinement round without
// the robust loss, then observations still above chi-square 5.991 (or behind a camera) are erased.
#pragma once

#include <atomic>
#include <functional>

#include "beslam_orb/options.hpp"
#include "ground/ground_plane.hpp"
#include "map/map_fwd.hpp"
#include "objects/object_ba.hpp"

namespace beslam::orb::optimize {

// Local BA's solver: SchurLevenbergMarquardt (schur_lm.hpp: the same problem, both cores, about half the
// time; not for object landmarks or more than 60 moving keyframes, which go to Ceres) or Ceres.
enum class BaSolver { SchurLm, Ceres };
// The solver an option names (MappingOptions::local_ba_solver, LoopClosureOptions::global_ba_solver).
inline BaSolver baSolver(BundleAdjustmentSolver solver) {
  return solver == BundleAdjustmentSolver::Schur ? BaSolver::SchurLm : BaSolver::Ceres;
}

struct BundleAdjustmentOptions {
  BaSolver solver = BaSolver::SchurLm;
  int robust_iterations = 5;
  int refine_iterations = 10;
  double chi2_threshold = 5.991;
  int max_local_keyframes = 0;  // 0 = every covisible keyframe
  double trusted_weight = 1.0;  // information multiplier for points on static objects
  // Parked cars' metric 3D boxes hold a metric map's scale (off while object_range_sigma is 0), with
  // sigma = object_range_sigma + object_range_sigma_per_m * range:
  // - object_anchors: one anchor per parked car (its box centre in the world) that every keyframe's box of
  //   the car measures (BoxCentreCost; boxes in FeatureSet::object_boxes). Unbiased: a detector's box centre
  //   does not depend on how the car fills its box.
  // - object_range_priors: each keypoint on a parked car at the range where its ray enters the car's box
  //   (ObjectRangeCost, FeatureSet::object_range). Biased short: a car's visible surface lies behind its
  //   box's faces (windows, sloping screens, wheels; docs/metric-scale.md).
  double object_range_sigma = 0;
  double object_range_sigma_per_m = 0.02;
  bool object_anchors = true;
  bool object_range_priors = false;
  // LiDAR ranges (FeatureSet::lidar_range): each keypoint with one holds its map point at that range from
  // its keyframe (ObjectRangeCost), sigma = lidar_range_sigma + lidar_range_sigma_per_m * range; 0: off.
  double lidar_range_sigma = 0;
  double lidar_range_sigma_per_m = 0.005;
  // Object landmarks of the map (Map::objects()) as 4-DoF nodes with box and surface factors (off by default).
  objects::ObjectFactorOptions objects;
  // Concurrent mapping (local BA only): called after each pass (the robust one, the refining one), where
  // the solve reads and writes only its own copies of the map; and when *stop_early is set after the
  // robust pass, the refining pass is skipped (ORB-SLAM2's interrupted local BA). The outliers are still
  // removed and the result written back.
  std::function<void()> between_passes;
  const std::atomic<bool>* stop_early = nullptr;
};

struct BundleAdjustmentReport {
  int keyframes = 0, fixed_keyframes = 0, points = 0, observations = 0, outliers_removed = 0;
  int ground_keyframes = 0, ground_residuals = 0, object_range_residuals = 0, object_anchor_residuals = 0;
  int lidar_range_residuals = 0;
  int object_nodes = 0, object_box_factors = 0, object_surface_factors = 0;
  double initial_cost = 0, final_cost = 0;
  bool stopped_early = false;  // the refining pass was skipped (BundleAdjustmentOptions::stop_early)
};

// Optional ground prior for local BA: every moving keyframe whose ground plane (fitGroundPlane, near the
// reference normal, height within max_height_deviation of the reference) is found gets one Huber-robust
// residual per plane inlier holding the point at the reference height below the camera.
struct GroundPrior {
  GroundPlaneOptions plane;
  const GroundReference* reference = nullptr;  // must be ready()
};

BundleAdjustmentReport localBundleAdjustment(KeyFrame* kf, Map& map, const BundleAdjustmentOptions& options,
                                             const GroundPrior* ground = nullptr);

// Every keyframe and point; the origin keyframe fixed. Used right after initialisation (Ceres) and after a
// loop correction (LoopOptions::global_ba_solver). SchurLm takes Ceres' steps (the same minimum up to
// rounding) and solves a map of more than SchurLevenbergMarquardt::kMaxDensePoses keyframes block-sparse.
// From `options` it takes the solver, the chi-square threshold and the metric terms local BA has on a
// metric map (LocalMapper::metricTerms): the parked cars' keypoint ranges (object_range_sigma > 0 and
// object_range_priors), the keypoints' LiDAR ranges (lidar_range_sigma > 0), one anchor per parked car on its
// keyframes' boxes (object_range_sigma > 0 and object_anchors) and the object landmarks as nodes
// (objects.enabled; these go to Ceres). Its pass counts and hooks are not used.
BundleAdjustmentReport globalBundleAdjustment(Map& map, int iterations, const BundleAdjustmentOptions& options);

// A global BA's options without metric terms on the given solver (initialisation, tests).
inline BundleAdjustmentOptions plainOptions(BaSolver solver) {
  BundleAdjustmentOptions options;
  options.solver = solver;
  return options;
}

}  // namespace beslam::orb::optimize
