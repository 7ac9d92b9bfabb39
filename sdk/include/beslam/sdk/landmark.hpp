// Object landmarks (reconstructed static objects) and keyframes in C++ form; their C conversions are in
// detail/landmark.hpp.
#pragma once

#include <map>

#include "beslam/sdk/views.hpp"

namespace beslam::sdk {

// A map point a keyframe observes (ABI 1.3): the backend's id, world position, pixel and mask label.
struct KeyframePoint {
  int64_t id = -1;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector2f pixel = Eigen::Vector2f::Zero();
  uint16_t label = BESLAM_LABEL_BACKGROUND;  // BESLAM_LABEL_STATIC_BASE + track id on a static object
  int32_t observations = 0;
};

struct Keyframe {
  int64_t id = -1;
  int64_t frame_index = -1;
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  bool world_is_metric = false;       // T_world_cam in metres (BESLAM_WORLD_SCALE_METRIC)
  std::vector<KeyframePoint> points;  // what it observes (empty from a backend older than ABI 1.3)
  // ABI 1.6: every keyframe of the backend as it is now, this one included: frame index -> T_world_cam
  // (empty from an older host). Observations kept relative to a keyframe are placed with these.
  std::map<int64_t, Eigen::Isometry3d> T_world_cam_by_frame;
};

struct Landmark {
  int32_t track_id = -1;
  int32_t class_id = BESLAM_CLASS_CAR;
  float confidence = 0;
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  // x heading, y left, z up
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();                   // length, width, height
  std::vector<float> shape_code;
  std::vector<float> surface_points;  // x y z triples in the object frame
  bool removed = false;               // no landmark any more (it started to move): the backend drops it
  int32_t keyframes = 0;              // keyframes whose observations the estimate uses
  double cost = 0;                    // final cost of the fit
  std::vector<float> mesh_vertices;   // x y z triples in the object frame, metres
  std::vector<uint32_t> mesh_faces;   // vertex index triples, counter-clockwise seen from outside
};

}  // namespace beslam::sdk

#include "beslam/sdk/detail/landmark.hpp"
