// Bundle adjustment with Ceres over keyframe poses and map points.
// Local BA: the new keyframe and its covisible keyframes move, keyframes that see the same points but
// are not covisible stay fixed; a robust (Huber) round, outliers dropped, a refinement round without
// the robust loss, then observations still above chi-square 5.991 (or behind a camera) are erased.
#pragma once

#include <atomic>

namespace beslam::orb {
class KeyFrame;
class Map;
}  // namespace beslam::orb

namespace beslam::orb::optimize {

struct BundleAdjustmentOptions {
  int robust_iterations = 5;
  int refine_iterations = 10;
  double chi2_threshold = 5.991;
  int max_local_keyframes = 0;   // 0 = every covisible keyframe
  double trusted_weight = 1.0;   // information multiplier for points on static objects
};

struct BundleAdjustmentReport {
  int keyframes = 0, fixed_keyframes = 0, points = 0, observations = 0, outliers_removed = 0;
  double initial_cost = 0, final_cost = 0;
};

BundleAdjustmentReport localBundleAdjustment(KeyFrame* kf, Map& map, const BundleAdjustmentOptions& options);

// Every keyframe and point; the origin keyframe fixed. Used right after initialisation.
BundleAdjustmentReport globalBundleAdjustment(Map& map, int iterations, double chi2_threshold = 5.991);

}  // namespace beslam::orb::optimize
