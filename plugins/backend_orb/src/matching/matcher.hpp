// Descriptor matching, always restricted by geometry through the keypoint grid: a window around the
// same position (initialisation), a projection of map points (tracking, fusion) or an epipolar line
// (triangulation). Hamming thresholds 50 (strict) / 100 (loose), nearest-neighbour ratio tests and a
// rotation-consistency histogram reject ambiguous and wrong matches.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <set>
#include <utility>
#include <vector>

#include "beslam_orb/options.hpp"
#include "features/feature_set.hpp"
#include "features/scale_pyramid.hpp"
#include "map/map_fwd.hpp"

namespace beslam::orb {

namespace matching {

constexpr int kThLow = 50;
constexpr int kThHigh = 100;
constexpr int kHistogramBins = 30;

// Keeps the matches whose orientation difference falls in the three most populated of 30 bins.
class RotationHistogram {
 public:
  void add(float angle1, float angle2, int id);
  std::vector<int> rejected() const;  // ids outside the three strongest bins
 private:
  std::vector<int> bins_[kHistogramBins];
};

// Keypoints of f1 up to max_level against the same level of f2 within `window` px of prev_matched
// (updated with the matches); matches12[i1] = i2 or -1. Strict threshold, ratio test, rotation check.
int searchForInitialization(const FeatureSet& f1, const FeatureSet& f2, std::vector<cv::Point2f>& prev_matched,
                            std::vector<int>& matches12, int window, float ratio = 0.9f, int max_level = 0);

// Constant-velocity tracking: last frame's points projected with cur.T_cw, radius th x level scale.
int searchByProjection(Frame& cur, const Frame& last, const Camera& camera, const ScalePyramid& pyramid, float th);

// Local map: points already annotated (MapPoint::track_*) by the tracker's frustum test.
int searchLocalPoints(Frame& cur, const std::vector<MapPoint*>& points, const ScalePyramid& pyramid, float th,
                      float ratio = 0.8f);

// Points projected with pose T_cw inside a radius (x level scale), best under max_distance with a
// ratio test and rotation check: reference-keyframe tracking and relocalisation.
int searchByProjectionWide(Frame& cur, const std::vector<MapPoint*>& points, const Eigen::Isometry3d& T_cw,
                           const Camera& camera, const ScalePyramid& pyramid, float radius, float ratio,
                           int max_distance);

// Bag of words (ORB-SLAM2's SearchByBoW): each of kf's map points against the frame's keypoints under the
// same direct-index node; best under the strict threshold, ratio test, rotation check. Needs both direct
// indices. Sets cur.points (only slots still empty) and returns the number of matches.
int searchByBoW(const KeyFrame* kf, Frame& cur, float ratio, bool check_orientation = true);

// Unmatched keypoints of kf1 against unmatched keypoints of kf2 along epipolar lines (F21: x2' F21 x1 = 0).
// same_bow_node (ORB-SLAM2's candidates): only pairs under the same direct-index node, when both
// keyframes have one.
int searchForTriangulation(const KeyFrame* kf1, const KeyFrame* kf2, const Eigen::Matrix3d& F21,
                           std::vector<std::pair<int, int>>& matches, float ratio, bool check_orientation,
                           bool same_bow_node = false);

// The keypoint of kf that map point mp matches when projected with pose T_cw (its predicted level, a
// radius th x scale, reprojection chi-square 5.99, best under the strict threshold), skipping the
// keypoints in `taken`; -1 if none. The point must be in front, in the image, within its distance range
// and seen from less than 60 degrees off its mean viewing direction.
int bestKeypointFor(const KeyFrame* kf, const MapPoint* mp, const Eigen::Isometry3d& T_cw, float th,
                    const std::set<int>& taken = {});

// Projects points into kf; a match either adds an observation or merges duplicates (the point with
// more observations survives). Returns the number of fused points.
int fuse(KeyFrame* kf, const std::vector<MapPoint*>& points, float th = 3.0f);

}  // namespace matching
}  // namespace beslam::orb
