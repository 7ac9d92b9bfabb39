// Ground plane under a keyframe, from its map points, and the camera's height above it.
//
// Contract: fitGroundPlane() looks at the keyframe's own map points (and, with pool_keyframes, those of its
// covisible keyframes close in time) that lie at least `min_ray_below_horizon` (n_expected . p_cam / z)
// under the horizon, runs a seeded RANSAC over planes
// whose normal is within a given tilt of the expected down direction (the camera's +y axis until a
// reference exists, then the reference normal), keeps the plane with most inliers
// (|n . p_cam - h| < inlier_ratio * h) and refines it by least squares.
// The plane is n . p_cam = h with n a unit vector pointing down and h > 0 the camera height, both in the
// keyframe's camera frame and the map's (arbitrary monocular) unit. Deterministic for a given keyframe.
//
// Why: a monocular map's scale drifts, but a car-mounted camera keeps its height over the road. The
// height seen at the first keyframes is a reference that local BA can hold later keyframes to
// (optimize::GroundPrior), which ties the scale of the map along the whole run to its start.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "map/map_fwd.hpp"

namespace beslam::orb {

struct GroundPlaneOptions {
  bool enabled = false;                      // off: the ORB-SLAM2 rules alone
  double min_ray_below_horizon = 0.04;       // candidate points: y/z in the camera frame at least this
  double max_tilt_deg = 20.0;                // first fits: normal within this angle of the camera's +y axis
  double max_tilt_from_reference_deg = 4.0;  // later fits: within this angle of the reference normal
  double max_height_deviation = 0.2;         // later fits: |h / h_ref - 1| at most this, or not used
  double inlier_ratio = 0.03;                // inlier: |n . p - h| < ratio * h
  int min_inliers = 25;                      // fewer: no plane
  int ransac_iterations = 150;
  int reference_keyframes = 5;  // reference height: median over the first fits
  // Also the road points of covisible keyframes at most this many keyframes older or newer (each under the
  // horizon of a keyframe that sees it), in this keyframe's frame: a road is planar over a few metres, and a
  // keyframe alone may see too few road points (KITTI 06). 0: the keyframe's own points only.
  int pool_keyframes = 0;
  double sigma_ratio = 0.2;  // prior std-dev of one ground point's height, as a share of h
};

struct GroundPlane {
  Eigen::Vector3d normal_cam = Eigen::Vector3d::UnitY();  // unit, pointing down, camera frame
  double height = 0;                                      // camera height above the plane
  std::vector<MapPoint*> inliers;
};

// The median of a sample (the upper one of an even count), and the median absolute deviation from m: the
// robust centre and spread every scale estimate here uses. Empty samples are the caller's to avoid.
double median(std::vector<double> values);
double medianAbsoluteDeviation(const std::vector<double>& values, double m);

std::optional<GroundPlane> fitGroundPlane(const KeyFrame& kf, const GroundPlaneOptions& options,
                                          const Eigen::Vector3d& expected_normal_cam, double max_tilt_deg);

// The reference ground under the camera: once `keyframes` fits are in, the median height and the mean
// normal of those fits. Later fits are compared with it. With a finite max_spread the fits must agree
// (relative median absolute deviation at most that); until they do, the window slides over later fits.
class GroundReference {
 public:
  explicit GroundReference(int keyframes, double max_spread = 1e9) : needed_(keyframes), max_spread_(max_spread) {}
  void add(const GroundPlane& plane) { add(plane.height, plane.normal_cam); }
  // One sample of any positive quantity (a height, a scale ratio), with the normal it came with.
  void add(double value, const Eigen::Vector3d& normal = Eigen::Vector3d::UnitY());
  bool ready() const { return ready_; }
  double height() const { return height_; }
  double spread() const { return spread_; }  // relative MAD of the fits behind height()
  const Eigen::Vector3d& normal() const { return normal_; }
  // A known height (the rig's camera height once the map is metric); only a ready reference takes it.
  void setHeight(double h) {
    if (ready_) height_ = h;
  }
  // The map's unit became s times smaller: heights follow.
  void rescale(double s) {
    height_ *= s;
    for (double& h : heights_) h *= s;
  }

 private:
  int needed_;
  double max_spread_;
  double spread_ = 0;
  std::vector<double> heights_;
  std::vector<Eigen::Vector3d> normals_;
  bool ready_ = false;
  double height_ = 0;
  Eigen::Vector3d normal_ = Eigen::Vector3d::UnitY();
};

}  // namespace beslam::orb
