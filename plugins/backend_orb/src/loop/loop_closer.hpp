// LoopCloser: ORB-SLAM2's loop closing, run after local mapping on each new keyframe (inline in the
// deterministic mode, on the mapping thread in the threaded one: the tracker waits for it either way).
//
// 1. Detection: keyframes of the database that share words with the new keyframe, are not covisible with
//    it and score at least as well as its worst covisible neighbour; grouped with their covisible
//    neighbours (accumulated score >= 0.75 x the best group); a candidate must be consistent (its group
//    overlaps a candidate group of the previous keyframe) for `consistency` keyframes in a row.
// 2. Geometry: BoW matches between map points (>= 20), a seeded Sim3 RANSAC (SE3 once the map is
//    metric); on a metric map, when that finds no transform, the new keyframe's pose from the loop
//    keyframe's points in its image (BoW matches to every keypoint, EPnP RANSAC, pose optimisation: >= 20);
//    then the loop keyframe's neighbourhood projected into the new keyframe: >= 40 matches.
// 3. The BEV object check (BE-SLAM): parked cars (static-object map points, grouped by object) that the
//    loop keyframe's neighbourhood sees must, after the loop transform, lie near the ones the new
//    keyframe sees; a candidate whose parked cars mostly disagree is rejected and counted.
// 4. Correction: the new keyframe's neighbourhood moves with the loop transform, loop points are fused,
//    the essential graph (spanning tree, loop links, covisibility >= 100) is optimised with Ceres, map
//    points follow their reference keyframe, then a global bundle adjustment.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "beslam_orb/options.hpp"
#include "features/scale_pyramid.hpp"
#include "loop/sim3.hpp"
#include "map/map_fwd.hpp"
#include "optimize/bundle_adjustment.hpp"

namespace beslam::orb {

struct LoopOptions {
  int min_keyframes_since_loop = 10;  // no detection within this many keyframes of the last loop
  int consistency = 3;                // keyframes in a row whose candidate groups overlap
  int min_bow_matches = 20;
  int min_sim3_inliers = 20;
  int min_total_matches = 40;  // BoW inliers + projection matches of the loop neighbourhood
  bool object_check = true;
  double object_radius = 2.5;            // m (metric map) or map units: a parked car "agrees" within this
  double object_max_disagreement = 0.5;  // reject when more than this share of shared-view cars disagree
  int object_min_cars = 2;               // the check needs at least this many cars on both sides
  int pose_graph_iterations = 20;
  int global_ba_iterations = 10;  // 0: no global BA after the pose graph
  optimize::BaSolver global_ba_solver = optimize::BaSolver::SchurLm;
  // The metric terms the global BA keeps from local BA (LocalMapper::metricTerms): the keypoints' LiDAR ranges
  // while the scan holds the map's scale and, with global_ba_objects, the parked cars' anchors (or their keypoint
  // ranges, object_scale_hold: ranges) and the object landmarks once the map is metric. No callback: none.
  std::function<optimize::BundleAdjustmentOptions()> metric_terms;
  bool global_ba_objects = true;
  uint64_t seed = 1;
};

struct LoopClosureEvent {
  long keyframe_id = 0, loop_keyframe_id = 0;
  int64_t frame_index = 0, loop_frame_index = 0;
  int matches = 0;
  double correction_m = 0, correction_deg = 0, scale = 1;  // the new keyframe's pose change
  int keyframes = 0;                                       // in the map when the loop was closed
  double correct_ms = 0;                                   // the correction: fusion, essential graph, global BA
};

struct LoopStats {
  int candidates_checked = 0;  // consistent candidates that reached the geometric check
  int object_rejections = 0;   // candidates the BEV object check refused
  std::vector<LoopClosureEvent> closures;
};

class LoopCloser {
 public:
  LoopCloser(Map& map, KeyFrameDatabase& database, const ScalePyramid& pyramid, const LoopOptions& options);

  // Looks for a loop at kf (already processed by local mapping and in the database) and closes it.
  // metric: the map is in metres (SE3 loop transform, scale fixed in the pose graph). True when closed.
  bool process(KeyFrame* kf, bool metric);

  const LoopStats& stats() const { return stats_; }
  // The last process()'s stage times (ms): "loop_query" (database query and consistency), "loop_check"
  // (the candidates' geometry and object checks) and, when a loop was closed, "loop_correct".
  const std::vector<std::pair<std::string, double>>& lastTimings() const { return timings_; }
  // The keyframes' poses (by id) before the last process() closed a loop (empty otherwise), so the
  // tracker's frames can follow their reference keyframe.
  const std::map<long, Eigen::Isometry3d>& posesBefore() const { return poses_before_; }
  // The map was reset: forget candidate groups and the last loop.
  void reset();

 private:
  struct Group {
    std::set<long> keyframe_ids;
    int consistency = 0;
  };
  struct Hypothesis {
    loop::Sim3 S_cur_loop;                           // maps the loop keyframe's camera frame into the new one's
    std::vector<std::pair<int, MapPoint*>> matches;  // new keyframe keypoint -> loop map point (inliers)
  };
  std::vector<KeyFrame*> detect(KeyFrame* kf);
  std::optional<Hypothesis> fromPointMatches(KeyFrame* kf, KeyFrame* loop_kf, bool metric, bool debug);
  std::optional<Hypothesis> fromImageMatches(KeyFrame* kf, KeyFrame* loop_kf, bool debug);
  bool close(KeyFrame* kf, KeyFrame* loop_kf, const loop::Sim3& S_cur_loop, bool metric,
             const std::vector<std::pair<int, MapPoint*>>& matches);

  Map& map_;
  KeyFrameDatabase& database_;
  const ScalePyramid& pyramid_;
  LoopOptions options_;
  std::vector<std::pair<std::string, double>> timings_;
  LoopStats stats_;
  std::vector<Group> groups_;
  std::map<long, Eigen::Isometry3d> poses_before_;
  long last_loop_kf_id_ = -1;
  uint64_t ransac_calls_ = 0;
};

}  // namespace beslam::orb
