// The C view (beslam_object_landmark) of an object landmark held in C++: the SDK's Landmark a
// reconstructor returns, or the host's copy it hands to a backend. The pointers borrow the landmark's
// vectors, which must outlive the view; `size` and `flags` are passed because the two C++ types name
// them differently (scale / size, removed / flags).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "beslam/data.h"
#include "beslam/formats/geometry.hpp"

namespace beslam::sdk::detail {

template <class L>
beslam_object_landmark landmarkView(const L& l, const Eigen::Vector3d& size, uint32_t flags) {
  beslam_object_landmark c{};
  c.struct_size = sizeof(c);
  c.track_id = l.track_id;
  c.class_id = l.class_id;
  c.confidence = l.confidence;
  c.T_world_object = formats::toPose(l.T_world_object);
  for (int i = 0; i < 3; ++i) c.scale[i] = size[i];
  c.shape_code = l.shape_code.empty() ? nullptr : l.shape_code.data();
  c.shape_code_size = static_cast<uint32_t>(l.shape_code.size());
  c.surface_points = l.surface_points.empty() ? nullptr : l.surface_points.data();
  c.surface_point_count = l.surface_points.size() / 3;
  c.flags = flags;
  c.keyframes = l.keyframes;
  c.cost = l.cost;
  c.mesh_vertices = l.mesh_vertices.empty() ? nullptr : l.mesh_vertices.data();
  c.mesh_vertex_count = static_cast<uint32_t>(l.mesh_vertices.size() / 3);
  c.mesh_faces = l.mesh_faces.empty() ? nullptr : l.mesh_faces.data();
  c.mesh_face_count = static_cast<uint32_t>(l.mesh_faces.size() / 3);
  return c;
}

}  // namespace beslam::sdk::detail
