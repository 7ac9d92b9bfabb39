#include "objects/object_store.hpp"

#include <algorithm>
#include <cmath>

#include "beslam/sdk/views.hpp"

namespace beslam::recon {

bool isCarLike(int32_t class_id) { return class_id == BESLAM_CLASS_CAR || class_id == BESLAM_CLASS_VAN; }

Eigen::Isometry3d ObjectRecord::boxPose() const {
  // Median of each centre coordinate (robust to one bad box); heading: circular mean of the x axes in the
  // plane of the newest box's up axis (boxes are level in the camera frame, so all share it).
  const Eigen::Isometry3d newest = boxes.back().T_world_obj();
  const Eigen::Vector3d up = newest.linear().col(2);
  Eigen::Vector3d centre;
  for (int k = 0; k < 3; ++k) {
    std::vector<double> v;
    for (const BoxObservation& b : boxes) v.push_back(b.T_world_obj().translation()[k]);
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    centre[k] = v[v.size() / 2];
  }
  // Heading: boxes may flip front and back between detections; align each to the newest before averaging.
  const Eigen::Vector3d ref = newest.linear().col(0);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const BoxObservation& b : boxes) {
    Eigen::Vector3d x = b.T_world_obj().linear().col(0);
    x -= up * up.dot(x);
    sum += x.dot(ref) < 0 ? -x : x;
  }
  Eigen::Vector3d x = sum.norm() > 1e-9 ? sum.normalized() : ref;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = up.cross(x).normalized();
  T.linear().col(2) = up;
  T.translation() = centre;
  return T;
}

Eigen::Vector3d ObjectRecord::boxSize() const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const BoxObservation& b : boxes) sum += b.size;
  return sum / double(boxes.size());
}

size_t ObjectRecord::lidarPointCount() const {
  size_t n = 0;
  for (const LidarObservation& l : lidar) n += l.p_cam.size();
  return n;
}

std::vector<Eigen::Vector3d> ObjectRecord::lidarPoints() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(lidarPointCount());
  for (const LidarObservation& l : lidar)
    for (const Eigen::Vector3d& p_cam : l.p_cam) out.push_back(l.T_world_cam * p_cam);
  return out;
}

std::vector<Eigen::Vector3d> ObjectRecord::surfaceObservations(double map_point_margin) const {
  if (lidarPointCount() > 0) return lidarPoints();
  std::vector<Eigen::Vector3d> out;
  if (boxes.empty()) return out;
  const Eigen::Isometry3d T_obj_world = boxPose().inverse();
  const Eigen::Vector3d half = boxSize() / 2 + Eigen::Vector3d::Constant(map_point_margin);
  for (const auto& [id, m] : map_points) {
    const Eigen::Vector3d p = m.p_world();
    if (((T_obj_world * p).cwiseAbs() - half).maxCoeff() <= 0) out.push_back(p);
  }
  return out;
}

std::vector<WorldSilhouetteRay> ObjectRecord::silhouetteRays() const {
  std::vector<WorldSilhouetteRay> out;
  for (const SilhouetteObservation& s : silhouettes)
    for (size_t i = 0; i < s.sample.u_cam.size(); ++i)
      out.push_back({s.T_world_cam.translation(), s.T_world_cam.linear() * s.sample.u_cam[i], s.sample.inside[i] != 0});
  return out;
}

std::set<int32_t> ObjectStore::observe(const KeyframeInput& input, std::vector<int32_t>& ended) {
  std::set<int32_t> updated;
  if (input.boxes == nullptr) return updated;
  for (const beslam_box3d& box : *input.boxes) {
    if (box.track_id < 0 || !isCarLike(box.class_id)) continue;
    if (box.motion_state == BESLAM_MOTION_DYNAMIC) {
      if (objects_.erase(box.track_id)) ended.push_back(box.track_id);
      continue;
    }
    if (box.motion_state != BESLAM_MOTION_STATIC) continue;
    const Eigen::Vector3d centre_cam(box.center_cam[0], box.center_cam[1], box.center_cam[2]);
    const double range = centre_cam.norm();
    if (!centre_cam.allFinite() || range > options_.max_range) continue;
    ObjectRecord& o = objects_[box.track_id];
    o.track_id = box.track_id;
    o.class_id = box.class_id;
    o.last_keyframe = input.keyframe_id;
    const Eigen::Isometry3d T_cam_obj = sdk::objectPose(box);
    o.boxes.push_back({input.keyframe_id, input.frame_index, T_cam_obj, input.T_world_cam,
                       Eigen::Vector3d(box.size[0], box.size[1], box.size[2]), range});
    const uint16_t label = static_cast<uint16_t>(BESLAM_LABEL_STATIC_BASE + box.track_id);
    const Eigen::Isometry3d T_cam_world = input.T_world_cam.inverse();
    for (const KeyframeInput::Point& p : input.points)
      if (p.label == label && p.p_world.allFinite())
        o.map_points[p.id] = {input.frame_index, input.T_world_cam, T_cam_world * p.p_world};
    if (const auto sil = input.silhouettes.find(box.track_id);
        sil != input.silhouettes.end() && !sil->second.u_cam.empty() && options_.silhouette_keyframes > 0) {
      o.silhouettes.push_back({input.frame_index, input.T_world_cam, sil->second});
      if (o.silhouettes.size() > static_cast<size_t>(options_.silhouette_keyframes))
        o.silhouettes.erase(o.silhouettes.begin());
    }
    if (!input.lidar_cam.empty()) {  // returns inside the grown box, above the road
      const Eigen::Isometry3d T_obj_cam = T_cam_obj.inverse();
      const Eigen::Vector3d half(box.size[0] / 2 + options_.box_margin, box.size[1] / 2 + options_.box_margin,
                                 box.size[2] / 2 + options_.box_margin);
      const double floor = -box.size[2] / 2 + options_.road_clearance;
      LidarObservation scan{input.frame_index, input.T_world_cam, {}};
      for (const Eigen::Vector3d& p_cam : input.lidar_cam) {
        const Eigen::Vector3d p_obj = T_obj_cam * p_cam;
        if (std::abs(p_obj.x()) <= half.x() && std::abs(p_obj.y()) <= half.y() && p_obj.z() <= half.z() &&
            p_obj.z() >= floor)
          scan.p_cam.push_back(p_cam);
      }
      if (!scan.p_cam.empty()) o.lidar.push_back(std::move(scan));
      const size_t total = o.lidarPointCount();
      if (total > static_cast<size_t>(options_.max_lidar_points)) {  // keep every k-th, counted over all
        const size_t k = (total + options_.max_lidar_points - 1) / options_.max_lidar_points;
        size_t j = 0;
        for (LidarObservation& l : o.lidar) {
          std::vector<Eigen::Vector3d> thinned;
          for (const Eigen::Vector3d& p_cam : l.p_cam)
            if (j++ % k == 0) thinned.push_back(p_cam);
          l.p_cam.swap(thinned);
        }
        o.lidar.erase(
            std::remove_if(o.lidar.begin(), o.lidar.end(), [](const LidarObservation& l) { return l.p_cam.empty(); }),
            o.lidar.end());
      }
    }
    updated.insert(box.track_id);
  }
  return updated;
}

void ObjectStore::followKeyframes(const std::map<int64_t, Eigen::Isometry3d>& T_world_cam_by_frame) {
  if (T_world_cam_by_frame.empty()) return;
  const auto follow = [&](int64_t frame, Eigen::Isometry3d& T_world_cam) {
    const auto it = T_world_cam_by_frame.find(frame);
    if (it != T_world_cam_by_frame.end() && it->second.matrix().allFinite()) T_world_cam = it->second;
  };
  for (auto& [id, o] : objects_) {
    for (BoxObservation& b : o.boxes) follow(b.frame_index, b.T_world_cam);
    for (LidarObservation& l : o.lidar) follow(l.frame_index, l.T_world_cam);
    for (auto& [point, m] : o.map_points) follow(m.frame_index, m.T_world_cam);
    for (SilhouetteObservation& s : o.silhouettes) follow(s.frame_index, s.T_world_cam);
  }
}

const ObjectRecord* ObjectStore::find(int32_t track_id) const {
  const auto it = objects_.find(track_id);
  return it == objects_.end() ? nullptr : &it->second;
}

}  // namespace beslam::recon
