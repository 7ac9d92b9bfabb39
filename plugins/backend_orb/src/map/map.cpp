#include "map/map.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "map/frame.hpp"

namespace beslam::orb {

KeyFrame* Map::createKeyFrame(const Frame& frame, const Camera& camera, const ScalePyramid& pyramid) {
  return restoreKeyFrame(next_kf_id_, frame, camera, pyramid);
}

MapPoint* Map::createMapPoint(const Eigen::Vector3d& position, KeyFrame* reference) {
  return restoreMapPoint(next_point_id_, position, reference, reference ? reference->id : -1);
}

KeyFrame* Map::restoreKeyFrame(long id, const Frame& frame, const Camera& camera, const ScalePyramid& pyramid) {
  auto [it, inserted] = owned_keyframes_.emplace(id, nullptr);
  if (!inserted) throw std::logic_error("Map: keyframe id " + std::to_string(id) + " exists");
  it->second = std::make_unique<KeyFrame>(id, frame, camera, pyramid, this);
  KeyFrame* kf = it->second.get();
  if (keyframes_.empty() && !origin_) origin_ = kf;
  keyframes_.insert(kf);
  next_kf_id_ = std::max(next_kf_id_, id + 1);
  return kf;
}

MapPoint* Map::restoreMapPoint(long id, const Eigen::Vector3d& position, KeyFrame* reference, long first_keyframe_id) {
  auto [it, inserted] = owned_points_.emplace(id, nullptr);
  if (!inserted) throw std::logic_error("Map: map point id " + std::to_string(id) + " exists");
  it->second = std::make_unique<MapPoint>(id, position, reference, this, first_keyframe_id);
  MapPoint* mp = it->second.get();
  points_.insert(mp);
  next_point_id_ = std::max(next_point_id_, id + 1);
  return mp;
}

void Map::eraseKeyFrame(KeyFrame* kf) {
  if (keyframes_.erase(kf)) {
    culled_keyframes_.push_back(kf->id);
    ++culled_;
  }
}

void Map::eraseMapPoint(MapPoint* mp) {
  if (points_.erase(mp)) culled_points_.push_back(mp->id);
}

std::vector<KeyFrame*> Map::culledNotReleased() const {
  std::vector<KeyFrame*> out;
  for (long id : culled_keyframes_) out.push_back(owned_keyframes_.at(id).get());
  return out;
}

void Map::releaseCulled() {
  // Nothing live may point at what is freed. Links the culling left behind are cut first: a keyframe slot
  // still holding a culled point (a point matched at two keypoints of one keyframe keeps only one
  // observation, so culling clears only that slot), a live point observing or referenced to a culled
  // keyframe, a replacement chain through a culled point.
  for (KeyFrame* kf : keyframes_)
    for (MapPoint*& mp : kf->points)
      if (mp && mp->bad) mp = nullptr;
  for (MapPoint* mp : points_) {
    for (auto it = mp->observations.begin(); it != mp->observations.end();)
      it = it->first->bad ? mp->observations.erase(it) : std::next(it);
    if (mp->reference && mp->reference->bad)
      mp->reference = mp->observations.empty() ? nullptr : mp->observations.begin()->first;
    mp->replaced_by = nullptr;
  }
  for (long id : culled_points_) owned_points_.erase(id);
  for (long id : culled_keyframes_) owned_keyframes_.erase(id);
  culled_points_.clear();
  culled_keyframes_.clear();
}

void Map::clear() {
  keyframes_.clear();
  points_.clear();
  culled_keyframes_.clear();
  culled_points_.clear();
  owned_points_.clear();
  owned_keyframes_.clear();
  origin_ = nullptr;
  objects_.clear();
}

KeyFrame* Map::keyFrameFrom(long id) const {
  auto it = owned_keyframes_.lower_bound(id);
  return it == owned_keyframes_.end() ? nullptr : it->second.get();
}

void Map::rescale(double s) {
  for (auto& [id, kf] : owned_keyframes_) {
    kf->T_cw.translation() *= s;
    kf->T_cp.translation() *= s;
  }
  for (auto& [id, mp] : owned_points_) {
    mp->position *= s;
    mp->min_distance *= static_cast<float>(s);
    mp->max_distance *= static_cast<float>(s);
  }
  objects_.rescale(s, Eigen::Vector3d::Zero(), -1);
}

void Map::rescaleFrom(long first_kf_id, double s, const Eigen::Vector3d& c) {
  for (auto it = owned_keyframes_.lower_bound(first_kf_id); it != owned_keyframes_.end(); ++it) {
    KeyFrame& kf = *it->second;
    const Eigen::Vector3d centre = c + s * (kf.centre() - c);
    kf.T_cw.translation() = -(kf.T_cw.linear() * centre);
    kf.T_cp.translation() *= s;
  }
  for (auto& [id, mp] : owned_points_) {
    if (!mp->reference || mp->reference->id < first_kf_id) continue;
    mp->position = c + s * (mp->position - c);
    mp->min_distance *= static_cast<float>(s);
    mp->max_distance *= static_cast<float>(s);
  }
  objects_.rescale(s, c, first_kf_id);
}

int Map::dropObjectPoints(int32_t object_id) {
  std::vector<MapPoint*> doomed;
  for (MapPoint* mp : points_)
    if (!mp->bad && mp->object_id == object_id) doomed.push_back(mp);
  for (MapPoint* mp : doomed) mp->setBad();
  return static_cast<int>(doomed.size());
}

bool Map::hasLoop() const {
  for (const KeyFrame* kf : keyframes_)
    if (!kf->loop_edges.empty()) return true;
  return false;
}

}  // namespace beslam::orb
