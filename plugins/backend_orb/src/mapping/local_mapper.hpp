// Local mapping, run once per new keyframe: register its observations, cull recent points that are
// rarely found, triangulate new points with the best covisible keyframes (epipolar search), fuse
// duplicates with first- and second-order neighbours, local bundle adjustment, keyframe culling.
#pragma once

#include <list>
#include <string>
#include <utility>
#include <vector>

#include "beslam_orb/orb_slam.hpp"
#include "features/scale_pyramid.hpp"
#include "optimize/bundle_adjustment.hpp"

namespace beslam::orb {

class KeyFrame;
class Map;
class MapPoint;

struct LocalMapperOptions {
  int triangulation_neighbours = 20;
  float triangulation_ratio = 1.0f;
  double max_cos_parallax = 0.9998;
  bool triangulation_check_orientation = false;
  int fuse_neighbours = 20, fuse_second_order = 5;
  bool keyframe_culling = true;
  optimize::BundleAdjustmentOptions ba;
  GroundPlaneOptions ground;  // ground-height prior in local BA (off by default)
};

class LocalMapper {
 public:
  LocalMapper(Map& map, const Camera& camera, const ScalePyramid& pyramid, const LocalMapperOptions& options);

  // The whole pipeline for one keyframe. `run_ba` = false skips BA and culling (used for the initial map).
  void processKeyFrame(KeyFrame* kf, bool run_ba = true);
  void reset() {
    recent_.clear();
    ground_reference_ = GroundReference(options_.ground.reference_keyframes);
  }
  // Reference camera height of the ground prior (0 until the first fits have set it).
  double groundReferenceHeight() const { return ground_reference_.ready() ? ground_reference_.height() : 0; }

  // Timings (ms) of the last processKeyFrame, by stage.
  const std::vector<std::pair<std::string, double>>& lastTimings() const { return timings_; }
  int lastNewPoints() const { return last_new_points_; }

  // Stages, public for tests.
  void registerKeyFrame(KeyFrame* kf);
  void cullRecentPoints(KeyFrame* kf);
  int createNewPoints(KeyFrame* kf);
  void fuseWithNeighbours(KeyFrame* kf);
  int cullKeyFrames(KeyFrame* kf);

 private:
  Map& map_;
  Camera camera_;
  const ScalePyramid& pyramid_;
  LocalMapperOptions options_;
  std::list<MapPoint*> recent_;
  std::vector<std::pair<std::string, double>> timings_;
  int last_new_points_ = 0;
  GroundReference ground_reference_;
  optimize::BundleAdjustmentReport last_ba_;
};

}  // namespace beslam::orb
