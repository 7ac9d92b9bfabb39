// C conversions of keyframes and object landmarks (included by landmark.hpp).
#pragma once

#include "beslam/sdk/detail/landmark_view.hpp"

namespace beslam::sdk {

inline Keyframe toKeyframe(const beslam_keyframe& kf) {
  beslam_keyframe k{};
  std::memcpy(&k, &kf, std::min<size_t>(kf.struct_size, sizeof(k)));
  Keyframe out{k.id, k.frame_index, k.timestamp, toIsometry(k.T_world_cam), k.world_scale == BESLAM_WORLD_SCALE_METRIC,
               {}};
  if (k.points && k.point_size >= sizeof(beslam_keyframe_point))
    for (const beslam_keyframe_point& p : copyArray(k.points, k.point_count, k.point_size))
      out.points.push_back({p.id, Eigen::Vector3d(p.p_world[0], p.p_world[1], p.p_world[2]), Eigen::Vector2f(p.x, p.y),
                            p.label, p.observations});
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

// Views the landmarks as C structs; the vector of landmarks must outlive the result.
inline std::vector<beslam_object_landmark> toC(const std::vector<Landmark>& landmarks) {
  std::vector<beslam_object_landmark> out;
  out.reserve(landmarks.size());
  for (const Landmark& l : landmarks)
    out.push_back(detail::landmarkView(l, l.scale, l.removed ? BESLAM_LANDMARK_REMOVED : 0u));
  return out;
}

// Copies C landmarks (borrowed) into owned C++ ones.
inline std::vector<Landmark> fromC(const beslam_landmark_list* list) {
  std::vector<Landmark> out;
  if (list == nullptr) return out;
  for (const beslam_object_landmark& c : copyArray(list->landmarks, list->count, list->element_size)) {
    Landmark l;
    l.track_id = c.track_id;
    l.class_id = c.class_id;
    l.confidence = c.confidence;
    l.T_world_object = toIsometry(c.T_world_object);
    l.scale = Eigen::Vector3d(c.scale[0], c.scale[1], c.scale[2]);
    if (c.shape_code) l.shape_code.assign(c.shape_code, c.shape_code + c.shape_code_size);
    if (c.surface_points) l.surface_points.assign(c.surface_points, c.surface_points + 3 * c.surface_point_count);
    l.removed = c.flags & BESLAM_LANDMARK_REMOVED;
    l.keyframes = c.keyframes;
    l.cost = c.cost;
    if (c.mesh_vertices) l.mesh_vertices.assign(c.mesh_vertices, c.mesh_vertices + 3 * size_t(c.mesh_vertex_count));
    if (c.mesh_faces) l.mesh_faces.assign(c.mesh_faces, c.mesh_faces + 3 * size_t(c.mesh_face_count));
    out.push_back(std::move(l));
  }
  return out;
}

}  // namespace beslam::sdk
