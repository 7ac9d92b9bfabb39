// Options::validate: the constraints every option must meet, named in the error by the setting's name.
#include "beslam_orb/options.hpp"

#include <cmath>
#include <string>

namespace beslam::orb {

bool Options::validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  const ExtractorOptions& e = extractor;
  if (e.features < 100) return fail("features must be >= 100");
  if (init.features_factor < 1) return fail("init_features_factor must be >= 1");
  if (!(e.scale_factor > 1.0 && e.scale_factor < 2.0)) return fail("scale_factor must be in (1, 2)");
  if (e.levels < 1 || e.levels > 16) return fail("levels must be in [1, 16]");
  if (e.fast_initial < 1 || e.fast_fallback < 1 || e.static_object_fast < 1)
    return fail("FAST thresholds must be >= 1");
  if (e.fast_fallback > e.fast_initial) return fail("fast_fallback must be <= fast_initial");
  if (e.static_object_budget_share < 0 || e.static_object_budget_share > 1)
    return fail("static_object_budget_share must be in [0, 1]");
  if (static_object_weight <= 0) return fail("static_object_weight must be > 0");
  if (tracking.fps <= 0) return fail("fps must be > 0");
  if (tracking.min_tracked_inliers < 10) return fail("min_tracked_inliers must be >= 10");
  if (tracking.keyframe_min_gap < 1) return fail("keyframe_min_gap must be >= 1");
  if (tracking.keyframe_ref_ratio <= 0 || tracking.keyframe_ref_ratio > 1)
    return fail("keyframe_ref_ratio must be in (0, 1]");
  if (!(tracking.keyframe_floor_ratio >= 0)) return fail("keyframe_floor_ratio must be >= 0");
  if (mapping.triangulation_ratio <= 0 || mapping.triangulation_ratio > 1)
    return fail("triangulation_ratio must be in (0, 1]");
  if (mapping.triangulation_max_cos_parallax <= 0 || mapping.triangulation_max_cos_parallax >= 1)
    return fail("triangulation_max_cos_parallax must be in (0, 1)");
  if (mapping.triangulation_neighbours < 1) return fail("triangulation_neighbours must be >= 1");
  if (!(scale.ground_prior_sigma > 0) || !std::isfinite(scale.ground_prior_sigma))
    return fail("ground_prior_sigma must be > 0");
  if (scale.ground_reference_keyframes < 1) return fail("ground_reference_keyframes must be >= 1");
  if (scale.ground_min_inliers < 3) return fail("ground_min_inliers must be >= 3");
  if (scale.metric_scale && !(scale.camera_height > 0 && scale.camera_height < 100))
    return fail("metric_scale needs the camera's height over the road (dataset camera_height), in (0, 100) m");
  if (!(scale.metric_max_spread > 0)) return fail("metric_max_spread must be > 0");
  if (!(scale.object_range_sigma > 0) || !(scale.object_range_sigma_per_m >= 0))
    return fail("object_range_sigma must be > 0 and object_range_sigma_per_m >= 0");
  if (!(scale.lidar_range_sigma > 0) || !(scale.lidar_range_sigma_per_m >= 0))
    return fail("lidar_range_sigma must be > 0 and lidar_range_sigma_per_m >= 0");
  if (scale.lidar_reference_keyframes < 1 || scale.lidar_min_points < 3)
    return fail("lidar_reference_keyframes must be >= 1 and lidar_min_points >= 3");
  if (scale.lidar_points_per_keyframe < 1) return fail("lidar_points_per_keyframe must be >= 1");
  if (!(object_landmarks.pose_weight >= 0) || !(object_landmarks.surface_weight >= 0))
    return fail("object_pose_weight and object_surface_weight must be >= 0");
  if (!(object_landmarks.box_sigma > 0) || !(object_landmarks.box_sigma_per_m >= 0) ||
      !(object_landmarks.yaw_sigma_deg > 0) || !(object_landmarks.surface_sigma > 0) ||
      !(object_landmarks.surface_gate > 0))
    return fail(
        "object_box_sigma, object_yaw_sigma_deg, object_surface_sigma and object_surface_gate must be > 0, "
        "object_box_sigma_per_m >= 0");
  if (mapping.local_ba_iterations_robust < 0 || mapping.local_ba_iterations_refine < 0)
    return fail("BA iterations must be >= 0");
  if (mapping.local_ba_max_keyframes < 0) return fail("local_ba_max_keyframes must be >= 0");
  if (scale.ground_pool_keyframes < 0) return fail("ground_pool_keyframes must be >= 0");
  if (loop.own_stretch_keyframes < 0) return fail("loop_own_stretch_keyframes must be >= 0");
  if (init.min_parallax_deg <= 0) return fail("init_min_parallax_deg must be > 0");
  if (init.ransac_iterations < 1) return fail("ransac_iterations must be >= 1");
  return true;
}

}  // namespace beslam::orb
