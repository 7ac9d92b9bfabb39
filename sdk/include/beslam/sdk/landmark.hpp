// Object landmarks (reconstructed static objects) and keyframes in C++ form; their C conversions are in
// detail/landmark.hpp.
#pragma once

#include "beslam/sdk/plugin.hpp"

namespace beslam::sdk {

struct Keyframe {
  int64_t id = -1;
  int64_t frame_index = -1;
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  bool world_is_metric = false;  // T_world_cam in metres (BESLAM_WORLD_SCALE_METRIC)
};

struct Landmark {
  int32_t track_id = -1;
  int32_t class_id = BESLAM_CLASS_CAR;
  float confidence = 0;
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  // x heading, y left, z up
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();                   // length, width, height
  std::vector<float> shape_code;
  std::vector<float> surface_points;  // x y z triples in the object frame
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/landmark.hpp"
