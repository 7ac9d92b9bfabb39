#include "objects/object_store.hpp"

namespace beslam::orb::objects {

void ObjectStore::add(const ObjectLandmark& given, long last_kf_id) {
  if (!given.T_world_object.matrix().allFinite()) return;  // nothing to optimise
  ObjectLandmark landmark = given;
  landmark.points_object.clear();  // samples that are not finite or absurdly far from the centre are dropped
  for (const Eigen::Vector3d& p : given.points_object)
    if (p.allFinite() && p.norm() < 1e3) landmark.points_object.push_back(p);
  for (ObjectEntry& e : entries_)
    if (e.landmark.id == landmark.id) {
      e.landmark = landmark;
      e.since_kf_id = last_kf_id;
      e.index_stale = true;
      return;
    }
  ObjectEntry e;
  e.landmark = landmark;
  e.since_kf_id = last_kf_id;
  entries_.push_back(std::move(e));
}

bool ObjectStore::erase(int64_t id, long last_kf_id) {
  dropped_at_kf_[id] = last_kf_id;
  for (auto it = entries_.begin(); it != entries_.end(); ++it)
    if (it->landmark.id == id) {
      entries_.erase(it);
      return true;
    }
  return false;
}

long ObjectStore::boxesAfter(int64_t id) const {
  auto it = dropped_at_kf_.find(id);
  return it == dropped_at_kf_.end() ? -1 : it->second;
}

ObjectEntry* ObjectStore::find(int64_t id) {
  return const_cast<ObjectEntry*>(static_cast<const ObjectStore*>(this)->find(id));
}

const ObjectEntry* ObjectStore::find(int64_t id) const {
  for (const ObjectEntry& e : entries_)
    if (e.landmark.id == id) return &e;
  return nullptr;
}

std::vector<ObjectLandmark> ObjectStore::landmarks() const {
  std::vector<ObjectLandmark> out;
  out.reserve(entries_.size());
  for (const ObjectEntry& e : entries_) out.push_back(e.landmark);
  return out;
}

const SurfaceIndex& ObjectStore::surface(ObjectEntry& e, double radius) {
  if (e.index_stale || e.index.radius() != radius) {
    e.index = SurfaceIndex(e.landmark.points_object, radius);
    e.index_stale = false;
  }
  return e.index;
}

void ObjectStore::rescale(double s, const Eigen::Vector3d& c, long first_kf_id) {
  for (ObjectEntry& e : entries_) {
    if (e.since_kf_id < first_kf_id) continue;
    ObjectLandmark& l = e.landmark;
    l.T_world_object.translation() = c + s * (l.T_world_object.translation() - c);
    l.dimensions *= s;
    for (Eigen::Vector3d& p : l.points_object) p *= s;
    e.index_stale = true;
  }
}

void ObjectStore::followKeyFrames(const std::function<std::optional<Eigen::Isometry3d>(long)>& keyframe_motion) {
  for (ObjectEntry& e : entries_)
    if (const auto motion = keyframe_motion(e.since_kf_id)) {
      const Eigen::Isometry3d T = *motion * e.landmark.T_world_object;
      if (T.matrix().allFinite()) e.landmark.T_world_object = T;
    }
}

void ObjectStore::clear() {
  entries_.clear();
  dropped_at_kf_.clear();
}

}  // namespace beslam::orb::objects
