#include "object_outputs.hpp"

#include <cmath>
#include <filesystem>
#include <ostream>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/formats/geometry.hpp"
#include "beslam/formats/ply.hpp"

namespace fs = std::filesystem;

namespace beslam::pipeline::detail {

namespace {

std::string meshName(int32_t track_id) {
  std::string digits = std::to_string(track_id);
  if (digits.size() < 4) digits.insert(0, 4 - digits.size(), '0');
  return "objects/object_" + digits + ".ply";
}

// The object's mesh in its own frame.
formats::TriangleMesh objectMesh(const registry::ObjectLandmark& o) {
  formats::TriangleMesh mesh;
  for (size_t i = 0; i + 2 < o.mesh_vertices.size(); i += 3)
    mesh.vertices.emplace_back(o.mesh_vertices[i], o.mesh_vertices[i + 1], o.mesh_vertices[i + 2]);
  for (size_t i = 0; i + 2 < o.mesh_faces.size(); i += 3)
    mesh.faces.push_back({int(o.mesh_faces[i]), int(o.mesh_faces[i + 1]), int(o.mesh_faces[i + 2])});
  return mesh;
}

void checkLandmark(const std::string& path, const registry::ObjectLandmark& o) {
  const std::string what = "object " + std::to_string(o.track_id);
  if (!o.T_world_object.matrix().allFinite() || !o.scale.allFinite())
    throwAt(path, what + " has a non-finite pose or size");
  const size_t vertices = o.mesh_vertices.size() / 3;
  for (uint32_t index : o.mesh_faces)
    if (index >= vertices)
      throwAt(path, what + " has a mesh face index " + std::to_string(index) + " past its " + std::to_string(vertices) +
                        " vertices");
}

}  // namespace

void applyLandmarkUpdates(ObjectMap& objects, const registry::Landmarks& updates) {
  for (const registry::ObjectLandmark& l : updates) {
    if (l.removed)
      objects.erase(l.track_id);
    else
      objects[l.track_id] = l;
  }
}

void anchorLandmarkUpdates(ObjectAnchors& anchors, const registry::Landmarks& updates, const ObjectAnchor& keyframe) {
  for (const registry::ObjectLandmark& l : updates) {
    if (l.removed)
      anchors.erase(l.track_id);
    else
      anchors[l.track_id] = keyframe;
  }
}

void anchorFinalUpdates(ObjectAnchors& anchors, const registry::Landmarks& updates,
                        const std::map<int64_t, Eigen::Isometry3d>& T_world_cam_by_frame) {
  for (const registry::ObjectLandmark& l : updates) {
    const auto a = anchors.find(l.track_id);
    if (a == anchors.end()) continue;
    const auto then = T_world_cam_by_frame.find(a->second.frame_index);
    if (l.removed || then == T_world_cam_by_frame.end())
      anchors.erase(a);
    else
      a->second.T_world_cam_then = then->second;
  }
}

void followFinalPoses(ObjectMap& objects, const ObjectAnchors& anchors,
                      const std::vector<registry::PoseEntry>& final_poses) {
  std::map<int64_t, const Eigen::Isometry3d*> final_by_frame;
  for (const registry::PoseEntry& p : final_poses) final_by_frame[p.frame_index] = &p.T_world_cam;
  for (auto& [id, o] : objects) {
    const auto a = anchors.find(id);
    if (a == anchors.end()) continue;
    const auto f = final_by_frame.find(a->second.frame_index);
    if (f == final_by_frame.end()) continue;
    o.T_world_object = *f->second * a->second.T_world_cam_then.inverse() * o.T_world_object;
  }
}

nlohmann::json writeObjectOutputs(const std::string& out_dir, const ObjectMap& objects,
                                  const std::vector<beslam_map_point>& points) {
  const fs::path dir(out_dir);
  const std::string json_path = (dir / "objects.json").string();
  for (const auto& [id, o] : objects) checkLandmark(json_path, o);
  nlohmann::json list = nlohmann::json::array();
  size_t with_mesh = 0;
  for (const auto& [id, o] : objects) {
    nlohmann::json entry;
    entry["id"] = list.size();
    entry["track_id"] = o.track_id;
    entry["class"] = formats::className(o.class_id);
    entry["state"] =
        formats::motionName(BESLAM_MOTION_STATIC);  // a landmark is a static object; one that moved was removed
    std::vector<double> T(16);
    const Eigen::Matrix4d M = o.T_world_object.matrix();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) T[r * 4 + c] = M(r, c);
    entry["T_world_obj"] = T;
    entry["size"] = {o.scale.x(), o.scale.y(), o.scale.z()};
    entry["shape_code"] = o.shape_code;
    entry["keyframes"] = o.keyframes;
    entry["cost"] = o.cost;
    entry["confidence"] = o.confidence;
    entry["mesh"] = nullptr;
    if (!o.mesh_faces.empty()) {
      fs::create_directories(dir / "objects");
      formats::writePlyMesh((dir / meshName(o.track_id)).string(), objectMesh(o), o.T_world_object,
                            "BE-SLAM object " + std::to_string(o.track_id) + " (world frame, metres)");
      entry["mesh"] = meshName(o.track_id);
      ++with_mesh;
    }
    list.push_back(entry);
  }
  writeFileAtomic(json_path, nlohmann::json{{"frame", "world"}, {"unit", "metre"}, {"objects", list}}.dump(2) + "\n");
  if (with_mesh > 0) {  // map.ply: the map points, then every object's mesh (faces index into the one vertex list)
    formats::TriangleMesh all;
    for (const auto& p : points) all.vertices.emplace_back(p.p_world[0], p.p_world[1], p.p_world[2]);
    for (const auto& [id, o] : objects) {
      const int base = static_cast<int>(all.vertices.size());
      const formats::TriangleMesh mesh = objectMesh(o);
      for (const Eigen::Vector3d& v : mesh.vertices) all.vertices.push_back(o.T_world_object * v);
      for (const auto& f : mesh.faces) all.faces.push_back({base + f[0], base + f[1], base + f[2]});
    }
    formats::writePlyMesh((dir / "map.ply").string(), all, Eigen::Isometry3d::Identity(),
                          "BE-SLAM map points and object meshes (world frame, metres)");
  }
  return {{"reconstructed", objects.size()}, {"with_mesh", with_mesh}, {"file", "objects.json"}};
}

}  // namespace beslam::pipeline::detail
