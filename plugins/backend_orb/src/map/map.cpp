#include "map/map.hpp"

#include "map/frame.hpp"

namespace beslam::orb {

KeyFrame* Map::createKeyFrame(const Frame& frame, const Camera& camera, const ScalePyramid& pyramid) {
  all_keyframes_.push_back(std::make_unique<KeyFrame>(next_kf_id_++, frame, camera, pyramid, this));
  if (keyframes_.empty()) origin_ = all_keyframes_.back().get();
  keyframes_.insert(all_keyframes_.back().get());
  return all_keyframes_.back().get();
}

MapPoint* Map::createMapPoint(const Eigen::Vector3d& position, KeyFrame* reference) {
  all_points_.push_back(std::make_unique<MapPoint>(next_point_id_++, position, reference, this));
  points_.insert(all_points_.back().get());
  return all_points_.back().get();
}

void Map::clear() {
  // Objects stay allocated: frames and trajectory records may still point at them.
  keyframes_.clear();
  points_.clear();
  origin_ = nullptr;
}

void Map::rescale(double s) {
  for (auto& kf : all_keyframes_) {
    kf->T_cw.translation() *= s;
    kf->T_cp.translation() *= s;
  }
  for (auto& mp : all_points_) {
    mp->position *= s;
    mp->min_distance *= static_cast<float>(s);
    mp->max_distance *= static_cast<float>(s);
  }
}

void Map::rescaleFrom(long first_kf_id, double s, const Eigen::Vector3d& c) {
  for (size_t i = static_cast<size_t>(first_kf_id); i < all_keyframes_.size(); ++i) {
    KeyFrame& kf = *all_keyframes_[i];
    const Eigen::Vector3d centre = c + s * (kf.centre() - c);
    kf.T_cw.translation() = -(kf.T_cw.linear() * centre);
    kf.T_cp.translation() *= s;
  }
  for (auto& mp : all_points_) {
    if (!mp->reference || mp->reference->id < first_kf_id) continue;
    mp->position = c + s * (mp->position - c);
    mp->min_distance *= static_cast<float>(s);
    mp->max_distance *= static_cast<float>(s);
  }
}

int Map::dropObjectPoints(int32_t object_id) {
  std::vector<MapPoint*> doomed;
  for (MapPoint* mp : points_)
    if (!mp->bad && mp->object_id == object_id) doomed.push_back(mp);
  for (MapPoint* mp : doomed) mp->setBad();
  return static_cast<int>(doomed.size());
}

}  // namespace beslam::orb
