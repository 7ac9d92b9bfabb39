#include "beslam/static_map/static_map.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <unordered_set>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/sdk/views.hpp"

namespace beslam::static_map {

namespace {

bool isStatic(const beslam_box3d& box) { return box.motion_state == BESLAM_MOTION_STATIC; }

bool insideAnyMovingOrUnknown(const std::vector<beslam_box3d>& boxes, const Eigen::Vector3d& p_cam, double margin) {
  for (const beslam_box3d& b : boxes)
    if (!isStatic(b) && insideBox(b, p_cam, margin)) return true;
  return false;
}

// One key per voxel of edge `resolution`.
struct VoxelKey {
  int64_t operator()(const Eigen::Vector3f& p, float inv_res) const {
    const auto c = [&](float v) { return static_cast<int64_t>(std::floor(v * inv_res)) & 0x1fffff; };
    return (c(p.x()) << 42) | (c(p.y()) << 21) | c(p.z());
  }
};

}  // namespace

bool insideBox(const beslam_box3d& box, const Eigen::Vector3d& p_cam, double margin) {
  const Eigen::Vector3d p_box = sdk::boxPose(box).inverse() * p_cam;  // x length, y height, z width
  return std::abs(p_box.x()) <= box.size[0] / 2 + margin && std::abs(p_box.y()) <= box.size[2] / 2 + margin &&
         std::abs(p_box.z()) <= box.size[1] / 2 + margin;
}

StaticMapBuilder::StaticMapBuilder(const Options& options) : options_(options) {
  if (!(options.resolution > 0) || !(options.max_range > 0) || !(options.box_margin >= 0))
    throw Error("static map: resolution and max_range must be positive, box_margin not negative");
}

bool StaticMapBuilder::inView(const Eigen::Vector3d& p_cam) const {
  const beslam_camera& c = options_.camera;
  if (c.width <= 0 || c.height <= 0) return true;
  if (p_cam.z() < 0.5) return false;
  const double u = c.fx * p_cam.x() / p_cam.z() + c.cx, v = c.fy * p_cam.y() / p_cam.z() + c.cy;
  return u >= 0 && u < c.width && v >= 0 && v < c.height;
}

void StaticMapBuilder::addScan(int64_t frame_index, const float* xyzi, size_t count, size_t stride,
                               const Eigen::Isometry3d& T_cam_lidar, const std::vector<beslam_box3d>& boxes) {
  Scan scan;
  scan.origin_cam = T_cam_lidar.translation().cast<float>();
  const float inv_res = static_cast<float>(1.0 / options_.resolution);
  std::unordered_set<int64_t> seen;
  const auto* bytes = reinterpret_cast<const uint8_t*>(xyzi);
  for (size_t i = 0; i < count; ++i) {
    const float* p = reinterpret_cast<const float*>(bytes + i * stride);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
    const Eigen::Vector3d p_cam = T_cam_lidar * Eigen::Vector3d(p[0], p[1], p[2]);
    if (!inView(p_cam)) {
      ++stats_.points_outside_view;
      continue;
    }
    if (insideAnyMovingOrUnknown(boxes, p_cam, options_.box_margin)) {
      ++stats_.points_in_boxes;
      continue;
    }
    const Eigen::Vector3f q = p_cam.cast<float>();
    if (seen.insert(VoxelKey{}(q, inv_res)).second) scan.p_cam.push_back(q);
  }
  scans_[frame_index] = std::move(scan);
}

void StaticMapBuilder::addBoxes(int64_t frame_index, const std::vector<beslam_box3d>& boxes) {
  for (const beslam_box3d& b : boxes)
    if (!isStatic(b)) {
      boxes_[frame_index] = boxes;
      return;
    }
}

std::unique_ptr<octomap::OcTree> StaticMapBuilder::build(const std::map<int64_t, Eigen::Isometry3d>& T_world_cam,
                                                         const std::vector<Eigen::Vector3d>& map_points_world,
                                                         const std::vector<Eigen::Vector3d>& keyframe_centres) {
  auto tree = std::make_unique<octomap::OcTree>(options_.resolution);
  auto toOcto = [](const Eigen::Vector3d& p) { return octomap::point3d(float(p.x()), float(p.y()), float(p.z())); };
  if (!scans_.empty()) {
    for (const auto& [frame, scan] : scans_) {
      const auto pose = T_world_cam.find(frame);
      if (pose == T_world_cam.end()) continue;
      octomap::Pointcloud cloud;
      cloud.reserve(scan.p_cam.size());
      for (const Eigen::Vector3f& p : scan.p_cam) cloud.push_back(toOcto(pose->second * p.cast<double>()));
      tree->insertPointCloud(cloud, toOcto(pose->second * scan.origin_cam.cast<double>()), options_.max_range,
                             /*lazy_eval=*/true, /*discretize=*/true);
      ++stats_.scans;
      stats_.points_inserted += static_cast<int64_t>(scan.p_cam.size());
    }
    tree->updateInnerOccupancy();
    return tree;
  }
  // Map points: drop those inside a not-static box of any frame with a pose, then one ray each from the
  // nearest keyframe centre.
  std::vector<std::pair<Eigen::Isometry3d, const std::vector<beslam_box3d>*>> frames_with_boxes;
  for (const auto& [frame, boxes] : boxes_) {
    const auto pose = T_world_cam.find(frame);
    if (pose != T_world_cam.end()) frames_with_boxes.emplace_back(pose->second.inverse(), &boxes);
  }
  for (const Eigen::Vector3d& p_world : map_points_world) {
    bool in_box = false;
    for (const auto& [T_cam_world, boxes] : frames_with_boxes) {
      const Eigen::Vector3d p_cam = T_cam_world * p_world;
      if (p_cam.z() < -10 || p_cam.squaredNorm() > 100.0 * 100.0) continue;  // far from this frame's boxes
      if (insideAnyMovingOrUnknown(*boxes, p_cam, options_.box_margin)) {
        in_box = true;
        break;
      }
    }
    if (in_box) {
      ++stats_.points_in_boxes;
      continue;
    }
    const Eigen::Vector3d* origin = nullptr;
    double best = std::numeric_limits<double>::max();
    for (const Eigen::Vector3d& c : keyframe_centres)
      if ((c - p_world).squaredNorm() < best) best = (c - p_world).squaredNorm(), origin = &c;
    if (!origin) break;
    tree->insertRay(toOcto(*origin), toOcto(p_world), options_.max_range);
    ++stats_.map_points;
  }
  tree->updateInnerOccupancy();
  return tree;
}

void writeTree(const octomap::OcTree& tree, const std::string& path) {
  writeFileAtomic(path, [&](std::ostream& out) {
    if (!tree.writeBinaryConst(out)) throwAt(path, "OctoMap could not serialise the tree");
  });
}

std::unique_ptr<octomap::OcTree> readTree(const std::string& path) {
  const std::string bytes = readFile(path);
  std::istringstream in(bytes);
  auto tree = std::make_unique<octomap::OcTree>(0.1);
  if (bytes.rfind("# Octomap OcTree binary file", 0) != 0 || !tree->readBinary(in))
    throwAt(path, "not an OctoMap binary tree (.bt)");
  return tree;
}

}  // namespace beslam::static_map
