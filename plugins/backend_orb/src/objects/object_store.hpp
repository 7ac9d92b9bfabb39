// The map's object landmarks (parked cars a reconstructor made), in insertion order, each with the
// voxel index of its surface samples that local BA associates map points with.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <vector>

#include "beslam_orb/types.hpp"
#include "objects/surface_index.hpp"

namespace beslam::orb::objects {

struct ObjectEntry {
  ObjectLandmark landmark;
  long since_kf_id = 0;  // the newest keyframe when it was (last) added: scale corrections from there move it
  SurfaceIndex index;    // built by surface() for a given radius
  bool index_stale = true;
};

class ObjectStore {
 public:
  // Same id: replaces the landmark (the reconstructor refined it). last_kf_id: the map's newest keyframe.
  // A landmark with a non-finite pose is ignored; non-finite surface samples (or beyond 1 km) are dropped.
  void add(const ObjectLandmark& landmark, long last_kf_id);
  // Removes the landmark (the object started to move) and remembers that this object's boxes in keyframes
  // up to last_kf_id describe where it was parked before: a later landmark of the same id ignores them.
  bool erase(int64_t id, long last_kf_id);
  // Keyframes with an id above this may contribute boxes of object `id` (-1: all).
  long boxesAfter(int64_t id) const;
  ObjectEntry* find(int64_t id);
  const ObjectEntry* find(int64_t id) const;
  std::vector<ObjectEntry>& entries() { return entries_; }
  const std::vector<ObjectEntry>& entries() const { return entries_; }
  std::vector<ObjectLandmark> landmarks() const;
  size_t size() const { return entries_.size(); }
  // The surface index of an entry for this association radius (rebuilt when the radius or the object changed).
  static const SurfaceIndex& surface(ObjectEntry& e, double radius);

  // Map::rescale / rescaleFrom: object lengths follow the world's unit (X -> c + s (X - c) for positions).
  void rescale(double s, const Eigen::Vector3d& c, long first_kf_id);
  // A loop correction moved the keyframes: each landmark moves rigidly with the keyframe it was last added
  // at, as a map point moves with its reference keyframe. keyframe_motion(since_kf_id) gives that
  // keyframe's T_world_after * T_before_world, or nothing (the landmark stays where it is).
  void followKeyFrames(const std::function<std::optional<Eigen::Isometry3d>(long)>& keyframe_motion);
  void clear();

 private:
  std::vector<ObjectEntry> entries_;
  std::map<int64_t, long> dropped_at_kf_;
};

}  // namespace beslam::orb::objects
