// The static world as an OctoMap (output.octomap: static_map.bt, OctoMap's binary format).
//
// Built from LiDAR scans where the sequence has them, else from the SLAM map points. Scans: each
// keyframe's returns inside the camera's field of view (the only part the detector and motion checker
// judge: a car beside or behind the ego has no box), thinned to one point per voxel, are inserted with
// rays from the LiDAR origin (free space along the ray, occupied at its end, up to max_range). Map points: each is
// inserted with a ray from the nearest keyframe centre. Points inside the box of an object that is not called static
// (moving, or unknown: the platform cannot tell) are never inserted, so moving cars leave no trails; with no detector
// there are no boxes and everything is inserted. Poses are the backend's final ones, known only at the end of a run:
// scans wait in the camera frame until build().
#pragma once

#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "beslam/data.h"

namespace beslam::static_map {

struct Options {
  beslam_camera camera{};   // the field of view scans are cut to (width 0: no cut)
  double resolution = 0.2;  // voxel edge, metres
  double max_range = 40.0;  // metres: longer LiDAR rays are cut (free space up to here, no hit)
  double box_margin = 0.2;  // metres added around boxes of objects not called static
};

struct Stats {
  int64_t scans = 0;                // scans inserted
  int64_t points_inserted = 0;      // after thinning
  int64_t points_in_boxes = 0;      // dropped: inside a box of an object not called static
  int64_t points_outside_view = 0;  // dropped: outside the camera's field of view
  int64_t map_points = 0;           // map points inserted (no LiDAR)
};

// True when p_cam lies inside `box` grown by `margin` on every side.
bool insideBox(const beslam_box3d& box, const Eigen::Vector3d& p_cam, double margin);

class StaticMapBuilder {
 public:
  explicit StaticMapBuilder(const Options& options);

  // A keyframe's scan (x y z i floats in the LiDAR frame, `stride` bytes apart) and the frame's boxes
  // (camera frame). Points inside boxes not called static are dropped now; the rest is kept, thinned, in
  // the camera frame.
  void addScan(int64_t frame_index, const float* xyzi, size_t count, size_t stride,
               const Eigen::Isometry3d& T_cam_lidar, const std::vector<beslam_box3d>& boxes);
  // A frame's boxes, for the map-point route (kept only when some box is not static).
  void addBoxes(int64_t frame_index, const std::vector<beslam_box3d>& boxes);
  bool hasScans() const { return !scans_.empty(); }

  // The tree from the final poses (frames without a pose are skipped). With scans, the scans; else the
  // map points (world frame) with rays from the nearest of keyframe_centres.
  std::unique_ptr<octomap::OcTree> build(const std::map<int64_t, Eigen::Isometry3d>& T_world_cam,
                                         const std::vector<Eigen::Vector3d>& map_points_world,
                                         const std::vector<Eigen::Vector3d>& keyframe_centres);
  const Stats& stats() const { return stats_; }

 private:
  bool inView(const Eigen::Vector3d& p_cam) const;
  struct Scan {
    Eigen::Vector3f origin_cam;          // the LiDAR origin in the camera frame
    std::vector<Eigen::Vector3f> p_cam;  // thinned returns
  };
  Options options_;
  std::map<int64_t, Scan> scans_;
  std::map<int64_t, std::vector<beslam_box3d>> boxes_;  // frames with boxes not called static
  Stats stats_;
};

// Writes the tree in OctoMap's binary format, atomically; throws beslam::Error naming the path.
void writeTree(const octomap::OcTree& tree, const std::string& path);
// Reads a .bt file; throws beslam::Error naming the path when it is missing or not an OctoMap.
std::unique_ptr<octomap::OcTree> readTree(const std::string& path);

}  // namespace beslam::static_map
