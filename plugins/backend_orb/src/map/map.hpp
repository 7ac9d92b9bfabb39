// The map owns every keyframe and map point ever made (culled ones stay allocated, flagged bad, so
// pointers held by frames never dangle) and indexes the live ones.
#pragma once

#include <memory>
#include <set>
#include <vector>

#include "map/id_less.hpp"
#include "map/keyframe.hpp"
#include "map/map_point.hpp"

namespace beslam::orb {

class Map {
 public:
  KeyFrame* createKeyFrame(const Frame& frame, const Camera& camera, const ScalePyramid& pyramid);
  MapPoint* createMapPoint(const Eigen::Vector3d& position, KeyFrame* reference);
  void eraseKeyFrame(KeyFrame* kf) {
    keyframes_.erase(kf);
    ++culled_;
  }
  void eraseMapPoint(MapPoint* mp) { points_.erase(mp); }
  void clear();
  // Multiplies every length by s (keyframe and parent translations, point positions and their distance
  // ranges), culled objects included, so that the map's unit becomes s times smaller (metric scale).
  void rescale(double s);
  // Scale correction of the newer part of the map: keyframes from `first_kf_id` on and the points they made
  // are mapped by X -> c + s (X - c) (rotations kept); older keyframes and points stay. With c the current
  // camera's centre, whoever holds the current pose (the motion checker's world positions) sees no jump.
  void rescaleFrom(long first_kf_id, double s, const Eigen::Vector3d& c);
  // Marks bad every live map point made on static object `object_id` (it started to move).
  int dropObjectPoints(int32_t object_id);

  const std::set<KeyFrame*, IdLess<KeyFrame>>& keyframes() const { return keyframes_; }
  const std::set<MapPoint*, IdLess<MapPoint>>& points() const { return points_; }
  const std::vector<std::unique_ptr<KeyFrame>>& allKeyFrames() const { return all_keyframes_; }
  size_t numKeyFrames() const { return keyframes_.size(); }
  int culledKeyFrames() const { return culled_; }
  KeyFrame* origin() const { return origin_; }  // the first keyframe: fixed, never culled

 private:
  std::vector<std::unique_ptr<KeyFrame>> all_keyframes_;
  std::vector<std::unique_ptr<MapPoint>> all_points_;
  std::set<KeyFrame*, IdLess<KeyFrame>> keyframes_;
  std::set<MapPoint*, IdLess<MapPoint>> points_;
  long next_kf_id_ = 0, next_point_id_ = 0;
  int culled_ = 0;
  KeyFrame* origin_ = nullptr;
};

}  // namespace beslam::orb
