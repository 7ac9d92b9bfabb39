// A keyframe: a frame kept in the map with its features, matched map points, optimisable pose, its
// covisibility links (shared map points) and its place in the spanning tree.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "beslam_orb/options.hpp"
#include "features/feature_set.hpp"
#include "features/scale_pyramid.hpp"
#include "map/id_less.hpp"
#include "place/vocabulary.hpp"

namespace beslam::orb {

class MapPoint;
class Map;
struct Frame;

class KeyFrame {
 public:
  KeyFrame(long id, const Frame& frame, const Camera& camera, const ScalePyramid& pyramid, Map* map);
  ~KeyFrame();
  KeyFrame(const KeyFrame&) = delete;
  KeyFrame& operator=(const KeyFrame&) = delete;
  static long instances();  // keyframes allocated now, in every map (tests: culled ones are freed)

  const long id;
  const int64_t frame_index;
  const double timestamp;
  const std::shared_ptr<const FeatureSet> features;
  const Camera camera;
  const ScalePyramid& pyramid;
  Eigen::Isometry3d T_cw;
  std::vector<MapPoint*> points;  // per keypoint, may be null
  bool bad = false;
  Eigen::Isometry3d T_cp = Eigen::Isometry3d::Identity();  // to parent, set when culled
  place::BowVector bow;                                    // empty without a vocabulary
  place::FeatureVector feature_vector;                     // direct index

  // Spanning tree, and the keyframes this one closed a loop with (essential-graph edges).
  KeyFrame* parent = nullptr;
  std::set<KeyFrame*, IdLess<KeyFrame>> children;
  std::set<KeyFrame*, IdLess<KeyFrame>> loop_edges;

  // Scratch.
  int64_t track_ref_for_frame = -1;
  long fuse_target_for_kf = -1, ba_local_for_kf = -1, ba_fixed_for_kf = -1;

  Eigen::Vector3d centre() const { return T_cw.inverse().translation(); }
  size_t size() const { return points.size(); }
  const cv::KeyPoint& keypoint(size_t i) const { return features->keypoints[i]; }

  void addPoint(MapPoint* mp, size_t idx) { points[idx] = mp; }
  void erasePoint(size_t idx) { points[idx] = nullptr; }
  void erasePoint(MapPoint* mp);
  std::vector<MapPoint*> validPoints() const;  // non-null, not bad, each once
  int trackedPoints(int min_observations) const;
  double medianDepth(int q = 2) const;  // the 1/q quantile of point depths (2 = median)

  // Covisibility.
  void updateConnections();
  void addConnection(KeyFrame* kf, int weight);
  void eraseConnection(KeyFrame* kf);
  std::vector<KeyFrame*> covisibles() const { return ordered_; }
  std::vector<KeyFrame*> bestCovisibles(int n) const;
  int weight(KeyFrame* kf) const;
  const std::map<KeyFrame*, int, IdLess<KeyFrame>>& connections() const { return weights_; }

  void setBad();  // culls the keyframe: links, observations, children re-parented
  // Map loading: the covisibility weights and spanning-tree parent as they were saved (the parent's
  // children follow). The other side of each link is restored by that keyframe's own call.
  void restoreLinks(KeyFrame* parent, const std::map<KeyFrame*, int, IdLess<KeyFrame>>& weights);

 private:
  void sortConnections();
  std::map<KeyFrame*, int, IdLess<KeyFrame>> weights_;
  std::vector<KeyFrame*> ordered_;
  bool first_connection_ = true;
  Map* map_;
};

}  // namespace beslam::orb
