// What a run writes about its reconstructed objects (internal to the runner), from each object's latest
// landmark: objects.json (id, class, track id, state, T_world_obj 4x4 row-major, size, shape code,
// keyframes, cost, mesh file), objects/object_TTTT.ply (the mesh in the world frame, metres) and map.ply
// (map points and object meshes in one file). Every file is written atomically; a bad landmark (a mesh
// index past its vertices, a non-finite pose) is one beslam::Error naming the file and the object.
#pragma once

#include <Eigen/Geometry>
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

// The keyframe an object was last fitted from, and that keyframe's pose then (as the reconstructor was
// given it). A later loop correction moves the keyframe; the object, fitted in the world as it was then,
// moves with it (as a map point follows its reference keyframe), so that objects.json is in the final
// trajectory's world.
struct ObjectAnchor {
  int64_t frame_index = -1;
  Eigen::Isometry3d T_world_cam_then = Eigen::Isometry3d::Identity();
};
using ObjectAnchors = std::map<int32_t, ObjectAnchor>;

// Records the keyframe behind each updated (not removed) landmark.
void anchorLandmarkUpdates(ObjectAnchors& anchors, const registry::Landmarks& updates, const ObjectAnchor& keyframe);

// The reconstructor's finish() updates are in the world of its last reconstruct() call: each keeps the
// keyframe it hangs on, whose pose then is the one that call was given (T_world_cam_by_frame); an anchor
// whose keyframe that call did not list is dropped (the object stays as fitted).
void anchorFinalUpdates(ObjectAnchors& anchors, const registry::Landmarks& updates,
                        const std::map<int64_t, Eigen::Isometry3d>& T_world_cam_by_frame);

// Every object moved by how much the final trajectory moved the keyframe it hangs on:
// T_world_obj <- T_final(kf) T_then(kf)^-1 T_world_obj. Objects whose keyframe is not in `final_poses`
// (or that have no anchor) stay as they are.
void followFinalPoses(ObjectMap& objects, const ObjectAnchors& anchors,
                      const std::vector<registry::PoseEntry>& final_poses);

// Writes objects.json, objects/ and map.ply into out_dir; returns the summary.json entry.
nlohmann::json writeObjectOutputs(const std::string& out_dir, const ObjectMap& objects,
                                  const std::vector<beslam_map_point>& points);

}  // namespace beslam::pipeline::detail
