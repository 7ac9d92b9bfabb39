// beslam::orb data types that cross the facade (include/beslam_orb/orb_slam.hpp) and that internal modules
// also take or return: a frame's car boxes (ObjectBox), object landmarks (ObjectLandmark), and a tracked
// frame's result (TrackResult). Poses are named T_a_b (maps b's coordinates into a's): T_world_cam is the
// camera's pose in the world, T_cam_box a box's in the camera frame.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace beslam::orb {

enum class TrackingState { NotInitialized, Ok, Lost };

// A metric 3D box of a tracked car in the frame being tracked (camera frame). Every car's centre over time
// feeds the parked-car scale estimate (scale/parked_car_scale.hpp) before the map is metric; keypoints on
// the mask label 1000 + object_id of a parked one get the metric range at which their ray enters its box:
// a scale source too, and a range prior in local BA once metric (docs/metric-scale.md).
struct ObjectBox {
  int32_t object_id = -1;                                       // track id (mask label 1000 + id)
  bool parked = false;                                          // called static: its keypoints get ranges
  Eigen::Isometry3d T_cam_box = Eigen::Isometry3d::Identity();  // box centre; axes along length, height, width
  Eigen::Vector3d size = Eigen::Vector3d::Zero();               // extent along the box's x, y, z axes
};

struct TrackResult {
  TrackingState state = TrackingState::NotInitialized;
  bool is_keyframe = false;
  int64_t keyframe_id = -1;                                       // when is_keyframe
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // valid when state == Ok
  int tracked_points = 0;                                         // pose inliers
  bool world_is_metric = false;                                   // T_world_cam (and the map) in metres
  int features = 0, features_static = 0;                          // keypoints; on static-object labels
  int features_lidar = 0;                                         // keypoints with a LiDAR range
  // Map points made from keyframes' LiDAR ranges since the last frame (ScaleOptions::lidar_points).
  int lidar_points = 0;
  int tracked_static = 0;                                // inliers on static-object map points
  std::vector<std::pair<std::string, double>> stage_ms;  // extract, track, local_map, mapping...
  bool relocalised = false;                              // this frame recovered from Lost
  bool loop_closed = false;      // a loop was closed before this frame was tracked (the map moved)
  double loop_correction_m = 0;  // then: how far the loop keyframe's centre moved
  // The metric world moved before this frame was tracked (a loop correction, a change of scale, and with
  // report_map_moves local BA under the last frame's reference keyframe): a point the world held at p is at
  // world_change_scale * (R * p) + t now, [R | t] = *S_new_old, exact about the last tracked camera. Empty
  // when nothing moved it, or the world was not metric before.
  std::optional<Eigen::Isometry3d> S_new_old;
  double world_change_scale = 1.0;
  int loop_object_rejections = 0;            // loop candidates the BEV object check refused since the last frame
  int relocalisation_object_rejections = 0;  // relocalisation candidates the parked-car check refused
  int object_landmarks = 0;                  // object landmarks in the map
  int object_factors = 0;                    // object factors (box and surface) in the last local BA before this frame
  // The frame's keypoints: pixel, mask label under it, matched to a map point (pose inlier), octave.
  struct Keypoint {
    float x = 0, y = 0;
    uint16_t label = 0;
    bool matched = false;
    uint8_t octave = 0;
  };
  std::vector<Keypoint> keypoints;
  // When is_keyframe: the map points the new keyframe observes (for a reconstructor): those it matched,
  // and the static-object points in its view (labelled by their object).
  struct ObservedPoint {
    int64_t id = -1;
    Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
    float x = 0, y = 0;  // pixel of the keypoint it was matched at
    uint16_t label = 0;  // mask label under it
    int observations = 0;
  };
  std::vector<ObservedPoint> keyframe_points;
};

// An object reconstructed by another module (a parked car), in world coordinates.
struct ObjectLandmark {
  int64_t id = 0;           // label value on the mask is 1000 + id
  double confidence = 1.0;  // the reconstruction's, in (0, 1]: scales the information of its factors
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  // body x forward, y left, z up; box centre
  Eigen::Vector3d dimensions = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> points_object;  // surface samples in the object frame
};

}  // namespace beslam::orb
