// LiDAR bird's-eye-view car detector (the core of the detector_lidar plugin; no PCL in this header).
//
// One scan in (x y z intensity, LiDAR frame), 3D car boxes out in the rectified camera frame (x right,
// y down, z forward; geometric centre, size = length width height, yaw = KITTI rotation_y):
//   1. drop non-finite points and points outside [min_range, max_range]; with a camera, keep only points
//      in front of it that project into the image (grown by fov_margin_px) or lie within fov_context of
//      its view (so cars cut by the image border keep their shape; only clusters seen in the image count);
//   2. ground removal: one RANSAC plane kept near-perpendicular to the camera's y axis (PCL), or a BEV grid
//      of local ground heights; points less than ground_threshold above the ground, or higher than
//      max_height, are dropped;
//   3. Euclidean clustering of what is left, thinned to one point per voxel (PCL, kd-tree);
//   4. box fitting in the BEV (x, z) plane: L-shape search (closeness criterion over headings), or OpenCV's
//      minimum-area rectangle for sparse clusters (or always); sides are grown toward the car size prior
//      only where no LiDAR ray passed through at body height (free space), and the rectangle side taken as
//      the car's length is the one whose free-space-bounded completion fits the size prior best;
//   5. car-sized clusters are kept (footprint, top and bottom height above ground), the rest dropped.
// A single scan gives no velocity and no front/back: yaw is reported in (-pi/2, pi/2].
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "beslam/data.h"

namespace beslam::detector_lidar {

struct Options {
  // Input selection.
  double min_range = 1.5;       // m, from the LiDAR
  double max_range = 60.0;      // m
  bool camera_fov_only = true;  // report only cars seen in the image (needs a camera)
  double fov_margin_px = 40.0;  // image grown by this many pixels on each side
  double fov_context = 5.0;     // m: points this far outside the image's view still shape the boxes

  // Ground removal.
  std::string ground_method = "ransac";  // "ransac" | "grid"
  double ground_threshold = 0.25;        // m: points at most this far above the ground are ground
  double max_ground_tilt_deg = 10.0;     // ransac: plane normal within this of the camera's y axis
  int ransac_iterations = 200;
  double grid_cell = 0.5;   // grid: cell size (m)
  int grid_radius = 6;      // grid: local ground = lowest point within this many cells
  double max_height = 3.0;  // m above ground; higher points (trees, signs) are dropped

  // Clustering (on a voxel-downsampled cloud).
  double voxel_size = 0.12;        // m; 0: no downsampling
  double cluster_tolerance = 0.5;  // m
  int min_cluster_points = 8;
  int max_cluster_points = 25000;

  // Box fitting.
  std::string box_fit = "lshape";  // "lshape" | "min_area"
  double angle_step_deg = 1.0;     // lshape heading search step
  int lshape_min_points = 40;      // lshape: clusters with fewer points get the minimum-area rectangle

  // Car gate (on the fitted footprint before growing) and prior size (length, width, height).
  double car_min_extent = 1.0;  // m: the larger footprint side must reach this
  double car_max_length = 6.5;  // m
  double car_max_width = 2.8;   // m
  double car_min_top = 0.9;     // m above ground: highest point of the cluster, at least
  double car_max_top = 2.0;     // m above ground: highest point of the cluster, at most
  double car_max_bottom = 1.6;  // m above ground: lowest point, at most (a car behind a car shows its roof)
  std::array<double, 3> car_size = {3.9, 1.6, 1.5};
  double car_min_length = 2.2;  // m: without free_space, a visible side shorter than this is grown
  double car_min_width = 1.2;

  // Free-space reasoning: a box may only grow where no LiDAR ray passed through at body height
  // (free_space_min_height..free_space_max_height above the ground); also picks which side is the length.
  bool free_space = true;
  double free_space_min_height = 0.4;  // m
  double free_space_max_height = 0.9;  // m
  int free_space_min_rays = 3;         // rays needed to call a place free

  // Boxes farther than this or with fewer points get BESLAM_BOX_UNCERTAIN.
  double uncertain_range = 40.0;
  int uncertain_points = 25;

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

struct Stats {
  std::size_t input_points = 0;
  std::size_t invalid_points = 0;  // NaN / inf coordinates
  std::size_t used_points = 0;     // after range and FOV selection (context band included)
  std::size_t ground_points = 0;
  std::size_t object_points = 0;  // above ground, below max_height
  std::size_t clusters = 0;
  std::size_t cars = 0;
  bool ground_found = false;
};

// A footprint rectangle in the BEV (x, z) plane of the camera frame.
struct Rect2 {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  Eigen::Vector2d axis = Eigen::Vector2d::UnitX();  // unit direction of the first side
  double extent_axis = 0;                           // side length along axis
  double extent_cross = 0;                          // side length across it
};

// L-shape fit (closeness criterion) of 2D points; heading searched over [0, 90) degrees in step_deg.
Rect2 fitLShape(const std::vector<Eigen::Vector2d>& points, double step_deg);
// Minimum-area enclosing rectangle (OpenCV).
Rect2 fitMinAreaRect(const std::vector<Eigen::Vector2d>& points);

class LidarDetector {
 public:
  // T_cam_lidar maps LiDAR points into the rectified camera frame. camera (may be null) enables the
  // field-of-view selection. Throws std::invalid_argument on bad options.
  LidarDetector(const Options& options, const Eigen::Isometry3d& T_cam_lidar,
                const std::optional<beslam_camera>& camera);

  // xyzi: count points, stride_floats floats apart (>= 4). Non-finite points are skipped and counted.
  // Returns car boxes (class CAR, track -1, motion unknown), nearest first.
  std::vector<beslam_box3d> detect(const float* xyzi, std::size_t count, std::size_t stride_floats = 4,
                                   Stats* stats = nullptr) const;

  const Options& options() const { return options_; }

 private:
  Options options_;
  Eigen::Isometry3d T_cam_lidar_;
  std::optional<beslam_camera> camera_;
};

}  // namespace beslam::detector_lidar
