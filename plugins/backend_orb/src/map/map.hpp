// The map owns every keyframe and map point and indexes the live ones. Culling (KeyFrame::setBad,
// MapPoint::setBad / replaceWith) only flags an object and moves it to the culled list: it stays allocated
// until releaseCulled(), which the owner (OrbSlam) calls at a safe point, with mapping idle and after the
// tracker and the mapper have dropped every pointer to culled objects (Tracker::forgetCulled,
// LocalMapper::forgetCulled). Memory then follows the live map, not everything ever made.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <vector>

#include "map/id_less.hpp"
#include "map/keyframe.hpp"
#include "map/map_point.hpp"
#include "objects/object_store.hpp"

namespace beslam::orb {

class Map {
 public:
  KeyFrame* createKeyFrame(const Frame& frame, const Camera& camera, const ScalePyramid& pyramid);
  MapPoint* createMapPoint(const Eigen::Vector3d& position, KeyFrame* reference);
  // Map loading (map_io): objects with the ids they had when saved. Ids must be new; the next ids made
  // by create*() continue after the largest restored one.
  KeyFrame* restoreKeyFrame(long id, const Frame& frame, const Camera& camera, const ScalePyramid& pyramid);
  MapPoint* restoreMapPoint(long id, const Eigen::Vector3d& position, KeyFrame* reference, long first_keyframe_id);
  void setOrigin(KeyFrame* kf) { origin_ = kf; }

  void eraseKeyFrame(KeyFrame* kf);  // called by KeyFrame::setBad
  void eraseMapPoint(MapPoint* mp);  // called by MapPoint::setBad / replaceWith
  // Frees every culled keyframe and map point. Precondition: nothing outside the map points at them
  // (live keyframes and points never do: culling unlinks them).
  void releaseCulled();
  std::vector<KeyFrame*> culledNotReleased() const;  // culled keyframes, not yet released
  bool hasCulled() const { return !culled_keyframes_.empty() || !culled_points_.empty(); }
  // Frees everything (tracker reset: its frames and records are cleared with it).
  void clear();
  // Multiplies every length by s (keyframe and parent translations, point positions and their distance
  // ranges), culled objects not yet released included, so that the map's unit becomes s times smaller.
  void rescale(double s);
  // Scale correction of the newer part of the map: keyframes from `first_kf_id` on and the points they made
  // are mapped by X -> c + s (X - c) (rotations kept); older keyframes and points stay. With c the current
  // camera's centre, whoever holds the current pose (the motion checker's world positions) sees no jump.
  void rescaleFrom(long first_kf_id, double s, const Eigen::Vector3d& c);
  // Marks bad every live map point made on static object `object_id` (it started to move).
  int dropObjectPoints(int32_t object_id);
  // Object landmarks (reconstructed parked cars), world frame: rescaled with the map, cleared with it.
  objects::ObjectStore& objects() { return objects_; }
  const objects::ObjectStore& objects() const { return objects_; }

  const std::set<KeyFrame*, IdLess<KeyFrame>>& keyframes() const { return keyframes_; }
  const std::set<MapPoint*, IdLess<MapPoint>>& points() const { return points_; }
  // The allocated keyframe with this id or, if it is gone, the first one after it (null: none).
  KeyFrame* keyFrameFrom(long id) const;
  long lastKeyFrameId() const { return next_kf_id_ - 1; }  // -1: none made yet
  size_t numKeyFrames() const { return keyframes_.size(); }
  bool hasLoop() const;  // a loop was closed in it (a live keyframe has a loop edge)
  int culledKeyFrames() const { return culled_; }
  // Allocated objects: the live ones plus those culled and not yet released.
  size_t allocatedKeyFrames() const { return owned_keyframes_.size(); }
  size_t allocatedPoints() const { return owned_points_.size(); }
  KeyFrame* origin() const { return origin_; }  // the first keyframe: fixed, never culled

 private:
  std::map<long, std::unique_ptr<KeyFrame>> owned_keyframes_;  // by id
  std::map<long, std::unique_ptr<MapPoint>> owned_points_;
  std::set<KeyFrame*, IdLess<KeyFrame>> keyframes_;
  std::set<MapPoint*, IdLess<MapPoint>> points_;
  std::vector<long> culled_keyframes_, culled_points_;  // ids waiting for releaseCulled()
  long next_kf_id_ = 0, next_point_id_ = 0;
  int culled_ = 0;
  KeyFrame* origin_ = nullptr;
  objects::ObjectStore objects_;
};

}  // namespace beslam::orb
