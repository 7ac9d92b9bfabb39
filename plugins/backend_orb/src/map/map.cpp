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

}  // namespace beslam::orb
