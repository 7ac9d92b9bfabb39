#include "objects/object_layout.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>

#include "map/camera_model.hpp"
#include "map/keyframe.hpp"
#include "map/map_point.hpp"
#include "objects/object_store.hpp"

namespace beslam::orb::objects {

std::vector<Eigen::Vector3d> parkedCarCentres(const KeyFrame& kf, const ObjectStore& store, int min_points) {
  std::map<int32_t, std::pair<Eigen::Vector3d, int>> sums;
  for (const MapPoint* mp : kf.validPoints()) {
    if (mp->object_id < 0 || !mp->trusted) continue;
    auto& [sum, n] = sums.try_emplace(mp->object_id, Eigen::Vector3d::Zero(), 0).first->second;
    sum += mp->position;
    ++n;
  }
  std::vector<Eigen::Vector3d> out;
  for (const auto& [id, s] : sums) {
    if (s.second < min_points) continue;
    const ObjectEntry* landmark = store.find(id);
    out.push_back(landmark ? landmark->landmark.T_world_object.translation() : Eigen::Vector3d(s.first / s.second));
  }
  return out;
}

std::vector<Eigen::Vector3d> carsInView(const std::vector<Eigen::Vector3d>& p_cam, const Camera& camera, double reach) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : p_cam) {
    if (p.z() < 1.0 || p.norm() > reach) continue;
    const Eigen::Vector2d uv = project(camera, p);
    if (inImage(camera, uv.x(), uv.y())) out.push_back(p);
  }
  return out;
}

LayoutCheck compareLayouts(const std::vector<Eigen::Vector3d>& expected, const std::vector<Eigen::Vector3d>& seen,
                           const LayoutOptions& options) {
  LayoutCheck c;
  if (static_cast<int>(expected.size()) < options.min_cars || static_cast<int>(seen.size()) < options.min_cars)
    return c;
  c.decided = true;
  c.compared = static_cast<int>(expected.size());
  for (const Eigen::Vector3d& p : expected) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& q : seen) nearest = std::min(nearest, (p - q).norm());
    if (nearest > options.radius) ++c.disagree;
  }
  c.rejected = c.disagree > options.max_disagreement * static_cast<double>(c.compared);
  return c;
}

}  // namespace beslam::orb::objects
