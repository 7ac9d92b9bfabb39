// fitObject: one car's pose, shape code (and optionally size) from surface observations and the shape
// prior (the surface and code terms of the paper's Algorithm 2; docs/reconstruction.md).
//
// Contract
// - Inputs in the world frame, metres. T_world_obj_init maps the object frame of shape/shape_prior.hpp
//   (x forward, y left, z up, origin at the box centre) into the world.
// - Energy (Levenberg-Marquardt, Ceres):
//     E = lambda_surface * sum_i w_i * huber((d_i / sigma_m)^2) + lambda_code * |z / codeStd|^2
//       [+ lambda_size * |log(size / size_init) / size_sigma|^2 when fit_size]
//       + lambda_render * sum_j w_j * huber(((D_j - depth_j) / sigma_depth_m)^2)
//       + lambda_silhouette * sum_k w_k * huber((v_k / sigma_silhouette_m)^2)
//       [+ |dt / box_sigma_m|^2 + (dyaw mod pi / box_sigma_yaw)^2 against the boxes' pose, when given]
//   with d_i = prior.distance(T_obj_world * p_i, size, z) in metres and D_j the depth rendered along ray j
//   (fit/render_depth.hpp). A depth ray that misses the shape at the current estimate adds nothing in that
//   iteration. v_k is the silhouette violation of ray k (fit/silhouette.hpp: the least of the prior's level
//   along the ray, scaled to metres at the start of each solve): for a ray through the car's mask, how far
//   it passes the surface; for a ray through the background beside the car, how deep it passes inside; 0
//   on the right side. The Huber threshold is huber_m (in metres of d). A first solve with a 4x wider
//   threshold pulls a far initial pose in; the second uses huber_m.
// - Pose: yaw_only (default) optimises the translation and the rotation about the object's own z axis
//   (the initial pose's up); roll and pitch stay those of the initial pose. Otherwise full 6-DoF.
// - Data problems never throw: no observations, a non-finite point, ray or weight, a weight outside
//   (0, 1], a non-positive depth, a ray without a unit direction, fewer than 4 points and rays (depth and
//   silhouette) together, a non-positive size, a code of the wrong length, a non-finite initial pose, bad
//   options or a failed solve give FitResult{ok = false, why = "..."} and leave the inputs as the result.
// - code_init: prior.dimensions() values, or empty for the mean shape (z = 0).
// - Deterministic (one thread).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "shape/shape_prior.hpp"

namespace beslam::recon::fit {

// One observed depth: the distance along a camera ray (a pixel in the car's mask) to the car's surface.
struct DepthRay {
  Eigen::Vector3d origin_world;     // the camera centre
  Eigen::Vector3d direction_world;  // unit length
  double depth_m = 0;               // along the ray (not the camera z), > 0
  double weight = 1;                // (0, 1]
};

// One silhouette sample: a camera ray through a pixel of the car's mask (inside: it must meet the car) or
// of the background beside it (it must pass the car).
struct SilhouetteRay {
  Eigen::Vector3d origin_world;     // the camera centre
  Eigen::Vector3d direction_world;  // unit length
  bool inside = true;
  double weight = 1;  // (0, 1]
};

struct FitObservations {                 // all world frame, metres
  std::vector<Eigen::Vector3d> p_world;  // surface observations: LiDAR points in the mask, or map points on the car
  std::vector<double> weight;            // per point, (0, 1], same size (or empty = all 1)
  // Where the detector's boxes put the car (their consensus), as a pose prior; none: no prior term.
  std::optional<Eigen::Isometry3d> T_world_obj_boxes;
  std::vector<DepthRay> rays;             // observed depths for the rendering term (may be empty)
  std::vector<SilhouetteRay> silhouette;  // mask and background rays for the silhouette term (may be empty)
};

struct FitOptions {
  double lambda_surface = 1.0;  // weight of the surface term
  double lambda_code = 1.0;     // weight of the code prior (|z / codeStd|^2)
  double sigma_m = 0.03;        // noise of one surface observation, metres
  double huber_m = 0.05;        // robust threshold on a distance, metres
  int max_iterations = 100;     // per solve (there are two)
  bool fit_size = false;        // also refine (l, w, h)
  double lambda_size = 1.0;     // weight of the size prior (fit_size)
  double size_sigma = 0.08;     // std of log(size / size_init)
  bool yaw_only = true;         // translation + yaw about the object's z; false: full 6-DoF
  double inlier_m = 0.10;       // |d| below this counts as an inlier
  // Box prior (with FitObservations::T_world_obj_boxes): centre offset / box_sigma_m and heading
  // difference / box_sigma_yaw, the heading taken modulo 180 degrees (a box's front and back may be
  // swapped; the surface decides which end is the nose).
  double box_sigma_m = 0.5;
  double box_sigma_yaw = 20.0 * M_PI / 180.0;
  double lambda_render = 1.0;        // weight of the rendering term (rays)
  double sigma_depth_m = 0.05;       // noise of one observed depth
  double huber_depth_m = 0.10;       // robust threshold on a depth difference
  double lambda_silhouette = 1.0;    // weight of the silhouette term
  double sigma_silhouette_m = 0.05;  // how far a ray may pass the wrong side of the surface (one sigma)
  double huber_silhouette_m = 0.10;  // robust threshold on that distance
  bool validate(std::string* why) const;
};

struct FitResult {
  bool ok = false;
  std::string why;  // why not ok
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::VectorXd code;
  double cost = 0;           // final E
  int inliers = 0;           // observations with |d| < inlier_m
  int silhouette_agree = 0;  // silhouette rays on their side of the surface, or within inlier_m of it
  double rms_m = 0;          // rms of d over all observations
  int iterations = 0;
};

// Largest prior dimension fitObject supports.
constexpr int kMaxFitDims = 10;

FitResult fitObject(const shape::ShapePrior& prior, const Eigen::Isometry3d& T_world_obj_init,
                    const Eigen::Vector3d& size, const Eigen::VectorXd& code_init, const FitObservations& observations,
                    const FitOptions& options);

}  // namespace beslam::recon::fit
