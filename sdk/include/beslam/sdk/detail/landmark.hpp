// C conversions of keyframes and object landmarks (included by landmark.hpp).
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace beslam::sdk {

inline Keyframe toKeyframe(const beslam_keyframe& kf) {
  beslam_keyframe k{};
  std::memcpy(&k, &kf, std::min<size_t>(kf.struct_size, sizeof(k)));
  Keyframe out{
      k.id, k.frame_index, k.timestamp, toIsometry(k.T_world_cam), k.world_scale == BESLAM_WORLD_SCALE_METRIC, {}, {}};
  if (k.points && k.point_size >= sizeof(beslam_keyframe_point))
    for (const beslam_keyframe_point& p : copyArray(k.points, k.point_count, k.point_size))
      out.points.push_back({p.id, Eigen::Vector3d(p.p_world[0], p.p_world[1], p.p_world[2]), Eigen::Vector2f(p.x, p.y),
                            p.label, p.observations});
  if (k.keyframe_poses && k.keyframe_pose_size >= sizeof(beslam_trajectory_entry))
    for (const beslam_trajectory_entry& e : copyArray(k.keyframe_poses, k.keyframe_pose_count, k.keyframe_pose_size))
      out.T_world_cam_by_frame[e.frame_index] = toIsometry(e.T_world_cam);
  return out;
}

inline beslam_keyframe_point toC(const KeyframePoint& p) {
  beslam_keyframe_point c{};
  c.id = p.id;
  for (int i = 0; i < 3; ++i) c.p_world[i] = p.p_world[i];
  c.x = p.pixel.x(), c.y = p.pixel.y();
  c.label = p.label;
  c.observations = p.observations;
  return c;
}

inline beslam_keyframe toC(const Keyframe& kf) {
  beslam_keyframe k{};
  k.struct_size = sizeof(k);
  k.id = kf.id;
  k.frame_index = kf.frame_index;
  k.timestamp = kf.timestamp;
  k.T_world_cam = toPose(kf.T_world_cam);
  k.world_scale = kf.world_is_metric ? BESLAM_WORLD_SCALE_METRIC : BESLAM_WORLD_SCALE_UNKNOWN;
  return k;
}

// The C view of one landmark: its pointers borrow the landmark's vectors, which must outlive it.
inline beslam_object_landmark toC(const Landmark& l) {
  beslam_object_landmark c{};
  c.struct_size = sizeof(c);
  c.track_id = l.track_id;
  c.class_id = l.class_id;
  c.confidence = l.confidence;
  c.T_world_object = formats::toPose(l.T_world_object);
  for (int i = 0; i < 3; ++i) c.scale[i] = l.scale[i];
  c.shape_code = l.shape_code.empty() ? nullptr : l.shape_code.data();
  c.shape_code_size = static_cast<uint32_t>(l.shape_code.size());
  c.surface_points = l.surface_points.empty() ? nullptr : l.surface_points.data();
  c.surface_point_count = l.surface_points.size() / 3;
  c.flags = l.removed ? BESLAM_LANDMARK_REMOVED : 0u;
  c.keyframes = l.keyframes;
  c.cost = l.cost;
  c.mesh_vertices = l.mesh_vertices.empty() ? nullptr : l.mesh_vertices.data();
  c.mesh_vertex_count = static_cast<uint32_t>(l.mesh_vertices.size() / 3);
  c.mesh_faces = l.mesh_faces.empty() ? nullptr : l.mesh_faces.data();
  c.mesh_face_count = static_cast<uint32_t>(l.mesh_faces.size() / 3);
  return c;
}

// Views the landmarks as C structs; the vector of landmarks must outlive the result.
inline std::vector<beslam_object_landmark> toC(const std::vector<Landmark>& landmarks) {
  std::vector<beslam_object_landmark> out;
  out.reserve(landmarks.size());
  for (const Landmark& l : landmarks) out.push_back(toC(l));
  return out;
}

// A C array of `count` values that must be there when count > 0, copied.
template <class T>
std::vector<T> copyValues(const T* data, uint64_t count, int32_t track_id, const char* what) {
  if (count == 0) return {};
  if (data == nullptr)
    throw std::invalid_argument("landmark " + std::to_string(track_id) + " has " + std::to_string(count) + " " + what +
                                " without data");
  return std::vector<T>(data, data + count);
}

// Copies C landmarks (borrowed; element_size as the other side was built, unknown trailing fields read
// as zero) into owned C++ ones. Counts without data and mesh faces past the vertices are refused with
// std::invalid_argument: the host and the backends read a plugin's landmarks through this one check.
inline std::vector<Landmark> fromC(const beslam_landmark_list* list) {
  std::vector<Landmark> out;
  if (list == nullptr || list->count == 0) return out;
  if (list->landmarks == nullptr || list->element_size < offsetof(beslam_object_landmark, flags))
    throw std::invalid_argument(std::to_string(list->count) + " landmarks without data");
  for (const beslam_object_landmark& c : copyArray(list->landmarks, list->count, list->element_size)) {
    Landmark l;
    l.track_id = c.track_id;
    l.class_id = c.class_id;
    l.confidence = c.confidence;
    l.T_world_object = toIsometry(c.T_world_object);
    l.scale = Eigen::Vector3d(c.scale[0], c.scale[1], c.scale[2]);
    l.removed = c.flags & BESLAM_LANDMARK_REMOVED;
    l.keyframes = c.keyframes;
    l.cost = c.cost;
    l.shape_code = copyValues(c.shape_code, c.shape_code_size, l.track_id, "shape code values");
    l.surface_points = copyValues(c.surface_points, 3 * c.surface_point_count, l.track_id, "surface point values");
    l.mesh_vertices = copyValues(c.mesh_vertices, 3 * uint64_t(c.mesh_vertex_count), l.track_id, "mesh vertex values");
    l.mesh_faces = copyValues(c.mesh_faces, 3 * uint64_t(c.mesh_face_count), l.track_id, "mesh face indices");
    for (uint32_t index : l.mesh_faces)
      if (index >= c.mesh_vertex_count)
        throw std::invalid_argument("landmark " + std::to_string(l.track_id) + " has a mesh face index " +
                                    std::to_string(index) + " past its " + std::to_string(c.mesh_vertex_count) +
                                    " vertices");
    out.push_back(std::move(l));
  }
  return out;
}

}  // namespace beslam::sdk
