// The reconstructor's memory of parked cars (Algorithm 2's bookkeeping): per motion-checker track, what
// the keyframes so far observed of it, in the world frame (metres).
//
// Contract
// - observe() takes one keyframe: its pose, its boxes (motion states and track ids from the motion
//   checker), the map points it observes with their mask labels, and the frame's LiDAR scan if any.
//   A car-like box called static within max_range adds a box observation, the keyframe's map points
//   labelled BESLAM_LABEL_STATIC_BASE + its track id, and the LiDAR returns inside the box (grown by
//   box_margin, without its lowest road_clearance metres). A box called dynamic ends its object: the
//   track id is returned in `ended` (a parked car that drives away stops being a landmark).
// - Association is by track id: a new id is a new object, a known id adds to it. Boxes without a track
//   id, of other classes or unknown motion are ignored.
// - Observations follow the map: boxes, LiDAR returns and map points are kept in the camera frame of the
//   keyframe that made (or last reported) them, with that keyframe's pose; followKeyframes() takes the
//   backend's keyframe poses as they are now (after local BA, loop corrections, rescaling), so a refit sees
//   them where the map has them. A keyframe the backend no longer has keeps its last known pose. Map points
//   are kept by id, at the position the latest keyframe to report them gave.
// - Silhouettes: a keyframe may carry, per track id, rays through pixels of the car's mask and of the
//   background beside it (the plugin samples them from the label mask); a static box keeps its track's,
//   the newest silhouette_keyframes of them per object.
// - Memory is bounded: LiDAR returns per object up to max_lidar_points (a deterministic thinning keeps every
//   k-th return, counted over the object's keyframes in order, when over).
// - Fits see LiDAR returns when the object has any, else its map points inside the boxes' consensus box
//   grown by map_point_margin.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "beslam/data.h"

namespace beslam::recon {

struct StoreOptions {
  double max_range = 30.0;        // m: farther boxes add nothing (their depth is poor)
  double box_margin = 0.15;       // m: LiDAR returns this far outside a box still count
  double road_clearance = 0.12;   // m: returns this close to the box bottom are road
  int max_lidar_points = 2000;    // per object
  double map_point_margin = 0.5;  // m: map points farther outside the consensus box are not the car's
  int silhouette_keyframes = 3;   // newest keyframes whose silhouettes an object keeps
};

// One keyframe's box of an object (landmark frame: x heading, y left, z up, centre), in that keyframe's
// camera frame, with the keyframe's pose as last known.
struct BoxObservation {
  int64_t keyframe_id = -1;
  int64_t frame_index = -1;
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // length, width, height
  double range = 0;                                // m from the camera
  Eigen::Isometry3d T_world_obj() const { return T_world_cam * T_cam_obj; }
};

// A map point on an object where the keyframe that last reported it put it, in that keyframe's camera frame.
struct MapPointObservation {
  int64_t frame_index = -1;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  Eigen::Vector3d p_cam = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_world() const { return T_world_cam * p_cam; }
};

// One keyframe's LiDAR returns on an object, in that keyframe's camera frame.
struct LidarObservation {
  int64_t frame_index = -1;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> p_cam;
};

// One keyframe's silhouette of an object: unit rays in that keyframe's camera frame, each through a pixel
// of the car's mask (inside) or of the background beside it.
struct SilhouetteSample {
  std::vector<Eigen::Vector3d> u_cam;
  std::vector<uint8_t> inside;  // per ray: 1 mask, 0 background
};

struct SilhouetteObservation {
  int64_t frame_index = -1;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  SilhouetteSample sample;
};

// A silhouette ray where its keyframe is now (world frame).
struct WorldSilhouetteRay {
  Eigen::Vector3d origin_world, direction_world;
  bool inside;
};

struct ObjectRecord {
  int32_t track_id = -1;
  int32_t class_id = BESLAM_CLASS_CAR;
  std::vector<BoxObservation> boxes;
  std::map<int64_t, MapPointObservation> map_points;  // by the backend's id
  std::vector<LidarObservation> lidar;
  std::vector<SilhouetteObservation> silhouettes;  // oldest first, at most silhouette_keyframes
  int64_t last_keyframe = -1;
  size_t lidarPointCount() const;
  std::vector<Eigen::Vector3d> lidarPoints() const;  // p_world, where their keyframes are now
  // The box observations' consensus: median centre, heading by circular mean, mean size.
  Eigen::Isometry3d boxPose() const;
  Eigen::Vector3d boxSize() const;
  // LiDAR points if any, else the map points inside the boxes' consensus box grown by map_point_margin
  // (a car's surface lies in its box: points labelled on it outside are mask bleed onto the background).
  std::vector<Eigen::Vector3d> surfaceObservations(double map_point_margin) const;
  std::vector<WorldSilhouetteRay> silhouetteRays() const;
};

struct KeyframeInput {
  int64_t keyframe_id = -1;
  int64_t frame_index = -1;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  const std::vector<beslam_box3d>* boxes = nullptr;
  struct Point {
    int64_t id;
    Eigen::Vector3d p_world;
    uint16_t label;
  };
  std::vector<Point> points;
  std::vector<Eigen::Vector3d> lidar_cam;           // the scan in the camera frame (empty: no scan)
  std::map<int32_t, SilhouetteSample> silhouettes;  // by track id (empty: none sampled)
};

class ObjectStore {
 public:
  explicit ObjectStore(const StoreOptions& options) : options_(options) {}
  // Adds a keyframe; returns the track ids of objects it updated and fills `ended` with objects it ended.
  std::set<int32_t> observe(const KeyframeInput& input, std::vector<int32_t>& ended);
  // Moves every observation to its keyframe's pose as given (frame index -> T_world_cam); keyframes not
  // given, or given a non-finite pose, keep their last known pose.
  void followKeyframes(const std::map<int64_t, Eigen::Isometry3d>& T_world_cam_by_frame);
  const ObjectRecord* find(int32_t track_id) const;
  const std::map<int32_t, ObjectRecord>& objects() const { return objects_; }

 private:
  StoreOptions options_;
  std::map<int32_t, ObjectRecord> objects_;
};

// True for the classes the shape prior describes (cars and vans).
bool isCarLike(int32_t class_id);

}  // namespace beslam::recon
