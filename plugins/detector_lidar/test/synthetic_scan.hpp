// A small LiDAR simulator for tests: a 64-beam spinning scanner (KITTI-like geometry) ray-cast against a
// flat ground and a set of boxes (cars, poles, pedestrians, walls), with ground-truth car boxes in the
// rectified camera frame of a KITTI-like camera.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "beslam/data.h"

namespace beslam::detector_lidar::synth {

struct Object {
  Eigen::Vector2d center_xy;  // LiDAR frame (x forward, y left), metres
  double yaw = 0;             // heading about LiDAR z (0: along x)
  double length = 4, width = 1.7, height = 1.5;
  double bottom = 0;  // height of the box bottom above the ground
  bool is_car = true;
};

struct Scene {
  std::vector<Object> objects;
  double lidar_height = 1.73;  // above the ground
  double noise = 0.02;         // range noise sigma (m)
};

// KITTI-like extrinsics and camera (1242x375, f 721).
Eigen::Isometry3d kittiLikeTcamLidar();
beslam_camera kittiLikeCamera();

// Random street: `cars` parked or driving cars within max_distance in the camera's view, plus poles,
// pedestrians and a wall as distractors. Deterministic for a seed.
Scene randomScene(uint32_t seed, int cars, double max_distance);

struct Scan {
  std::vector<float> xyzi;           // x y z intensity, LiDAR frame
  std::vector<int> hits_per_object;  // points that landed on each scene object
};

// Ray-casts the scene: 64 beams from +2 to -24.8 degrees, azimuth step az_step_deg over +-fov_deg.
Scan castScan(const Scene& scene, uint32_t seed, double az_step_deg = 0.16, double fov_deg = 55);

// Ground-truth boxes of the scene's cars in the camera frame (geometric centre, KITTI yaw).
std::vector<beslam_box3d> truthBoxes(const Scene& scene, const Eigen::Isometry3d& T_cam_lidar);

}  // namespace beslam::detector_lidar::synth
