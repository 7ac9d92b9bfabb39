#include "objects/object_ba.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "map/keyframe.hpp"
#include "map/map_point.hpp"
#include "objects/object_factors.hpp"

namespace beslam::orb::objects {

void ObjectProblem::writeBack() {
  for (size_t i = 0; i < entries.size(); ++i) {
    const double* x = node(i);
    bool finite = true;
    for (int k = 0; k < 4; ++k) finite = finite && std::isfinite(x[k]);
    if (finite) entries[i]->landmark.T_world_object = nodeToPose(R0[i], x);
  }
}

std::unique_ptr<ObjectProblem> buildObjectProblem(ObjectStore& store,
                                                  const std::map<KeyFrame*, double*, IdLess<KeyFrame>>& poses,
                                                  const std::set<const KeyFrame*>& moving,
                                                  const std::map<MapPoint*, double*, IdLess<MapPoint>>& positions,
                                                  const ObjectFactorOptions& options) {
  auto P = std::make_unique<ObjectProblem>();
  struct Pending {
    std::vector<std::pair<KeyFrame*, Eigen::Isometry3d>> boxes;  // keyframe, measured T_cam_object
    std::vector<std::pair<MapPoint*, size_t>> points;            // point, surface sample
    bool touches_moving = false;
  };
  std::vector<Pending> pending(store.size());
  std::map<int64_t, size_t> slot;
  for (size_t i = 0; i < store.size(); ++i) slot[store.entries()[i].landmark.id] = i;

  if (options.use_boxes)
    for (const auto& [kf, block] : poses) {
      if (kf->bad) continue;
      for (const ObjectBox& b : kf->features->object_boxes) {
        auto it = slot.find(b.object_id);
        if (it == slot.end() || kf->id <= store.boxesAfter(b.object_id)) continue;
        pending[it->second].boxes.emplace_back(kf, objectPoseOfBox(b));
        if (moving.count(kf)) pending[it->second].touches_moving = true;
      }
    }
  for (const auto& [mp, block] : positions) {
    if (mp->bad || mp->object_id < 0) continue;
    auto it = slot.find(mp->object_id);
    if (it == slot.end()) continue;
    ObjectEntry& e = store.entries()[it->second];
    if (e.landmark.points_object.empty()) continue;
    const SurfaceIndex& index = ObjectStore::surface(e, options.surface_gate);
    const Eigen::Vector3d p_object = e.landmark.T_world_object.inverse() * mp->position;
    if (const auto q = index.nearest(p_object)) {
      pending[it->second].points.emplace_back(mp, *q);
      pending[it->second].touches_moving = true;
    }
  }

  size_t n_nodes = 0;
  std::vector<size_t> node_of(store.size(), SIZE_MAX);
  for (size_t i = 0; i < store.size(); ++i) {
    const Pending& p = pending[i];
    const bool enough = !p.boxes.empty() || static_cast<int>(p.points.size()) >= options.min_surface_factors;
    if (enough && p.touches_moving && std::isfinite(store.entries()[i].landmark.confidence) &&
        store.entries()[i].landmark.confidence > 0)
      node_of[i] = n_nodes++;
  }
  P->storage.assign(4 * n_nodes, 0.0);  // allocated once: the factors keep pointers into it
  for (size_t i = 0; i < store.size(); ++i) {
    if (node_of[i] == SIZE_MAX) continue;
    ObjectEntry& e = store.entries()[i];
    const size_t n = node_of[i];
    P->entries.push_back(&e);
    P->R0.push_back(e.landmark.T_world_object.linear());
    double* x = P->node(n);
    x[0] = 0;
    for (int k = 0; k < 3; ++k) x[1 + k] = e.landmark.T_world_object.translation()[k];
    const double confidence = std::min(1.0, e.landmark.confidence);
    const double box_scale = std::sqrt(options.pose_weight * confidence);
    // The shape's own error (a fitted prior, decimetres) is common to every point on the car, so the car's
    // points together count as one observation of the surface, as the paper's 1/|P| writes E_surf; each
    // point its own would let 100 points outweigh every box and pull the map (docs/object-ba.md).
    const size_t n_points = std::max<size_t>(1, pending[i].points.size());
    const double surface_scale = std::sqrt(options.surface_weight * confidence / static_cast<double>(n_points));
    for (const auto& [kf, T_cam_object] : pending[i].boxes) {
      const double range = T_cam_object.translation().norm();
      const double sigma = options.box_sigma + options.box_sigma_per_m * range;
      ObjectProblem::Factor f;
      f.blocks.push_back(poses.at(kf));
      f.blocks.push_back(x);
      f.cost = std::make_unique<ObjectBoxCost>(T_cam_object, P->R0.back(), sigma, options.yaw_sigma, box_scale);
      f.huber = std::sqrt(9.488);
      P->factors.push_back(std::move(f));
      ++P->box_factors;
    }
    for (const auto& [mp, q] : pending[i].points) {
      ObjectProblem::Factor f;
      f.blocks.push_back(positions.at(mp));
      f.blocks.push_back(x);
      const Eigen::Vector3d& n = e.index.normal(q);
      f.cost =
          std::make_unique<SurfacePointCost>(e.index.point(q), n, P->R0.back(), options.surface_sigma, surface_scale);
      f.huber = n.squaredNorm() > 0 ? std::sqrt(3.841) : std::sqrt(7.815);
      P->factors.push_back(std::move(f));
      ++P->surface_factors;
    }
  }
  return P;
}

}  // namespace beslam::orb::objects
