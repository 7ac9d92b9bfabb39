// A 3D landmark: position, representative descriptor, mean viewing direction, the distance range over
// which its scale makes it detectable, and the keyframes that observe it (keypoint index in each).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>

#include "map/id_less.hpp"
#include "map/map_fwd.hpp"

namespace beslam::orb {

struct ScalePyramid;

using Descriptor = std::array<uint8_t, 32>;

class MapPoint {
 public:
  // first_keyframe_id: the id of the keyframe that made it (reference's id; another when loaded).
  MapPoint(long id, const Eigen::Vector3d& position, KeyFrame* reference, Map* map, long first_keyframe_id);
  ~MapPoint();
  MapPoint(const MapPoint&) = delete;
  MapPoint& operator=(const MapPoint&) = delete;
  static long instances();  // map points allocated now, in every map (tests: culled ones are freed)

  const long id;
  Eigen::Vector3d position;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // mean unit viewing direction (point - camera)
  float min_distance = 0, max_distance = 0;
  Descriptor descriptor{};
  std::map<KeyFrame*, size_t, IdLess<KeyFrame>> observations;
  KeyFrame* reference;
  const long first_keyframe_id;
  int visible = 1, found = 1;  // frames where predicted visible / actually matched
  bool bad = false;
  MapPoint* replaced_by = nullptr;
  bool trusted = false;  // created on a static object
  // Made from one keyframe's LiDAR range (LocalMapper::createRangedPoints, ScaleOptions::lidar_points), not
  // triangulated: its one observation already fixes it, as a stereo or RGB-D observation does in ORB-SLAM2.
  bool from_range = false;
  int32_t object_id = -1;  // that object's track id (mask label - 1000), -1 if none
  uint8_t grey = 0, r = 0, g = 0, b = 0;

  // Tracking scratch (per frame).
  bool track_in_view = false;
  float track_u = 0, track_v = 0, track_view_cos = 0;
  int track_level = 0;
  int64_t track_ref_for_frame = -1, last_seen_frame = -1;
  // Mapping scratch (per keyframe).
  long fuse_candidate_for_kf = -1, ba_local_for_kf = -1;

  void addObservation(KeyFrame* kf, size_t idx);
  void eraseObservation(KeyFrame* kf);  // sets bad when 2 or fewer remain
  bool isIn(const KeyFrame* kf) const;
  int index(const KeyFrame* kf) const;  // -1 if not observed
  int numObservations() const { return static_cast<int>(observations.size()); }
  void setBad();
  void replaceWith(MapPoint* other);
  MapPoint* latest();  // follow the replacement chain
  double foundRatio() const { return static_cast<double>(found) / visible; }

  void computeDistinctiveDescriptor();
  void updateNormalAndDepth();
  // A new point's last step, once its first observations are in: its colour (BGR of the keypoint it was
  // made from, grey their mean), its distinctive descriptor, its normal and distance range.
  void completeNewPoint(const std::array<uint8_t, 3>& bgr);
  int predictLevel(double distance, const ScalePyramid& pyramid) const;

 private:
  Map* map_;
};

}  // namespace beslam::orb
