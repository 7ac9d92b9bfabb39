// What a run writes about its reconstructed objects (internal to the runner), from each object's latest
// landmark: objects.json (id, class, track id, state, T_world_obj 4x4 row-major, size, shape code,
// keyframes, cost, mesh file), objects/object_TTTT.ply (the mesh in the world frame, metres) and map.ply
// (map points and object meshes in one file). Every file is written atomically; a bad landmark (a mesh
// index past its vertices, a non-finite pose) is one beslam::Error naming the file and the object.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "beslam/registry/instance.hpp"

namespace beslam::pipeline::detail {

// Latest landmark per track id, as a run collects them (removed objects are erased).
using ObjectMap = std::map<int32_t, registry::ObjectLandmark>;

// Applies a reconstructor's updates: a landmark replaces the one with its track id, a removed one erases it.
void applyLandmarkUpdates(ObjectMap& objects, const registry::Landmarks& updates);

// Writes objects.json, objects/ and map.ply into out_dir; returns the summary.json entry.
nlohmann::json writeObjectOutputs(const std::string& out_dir, const ObjectMap& objects,
                                  const std::vector<beslam_map_point>& points);

}  // namespace beslam::pipeline::detail
