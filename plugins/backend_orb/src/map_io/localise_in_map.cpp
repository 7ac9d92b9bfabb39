#include "map_io/localise_in_map.hpp"

#include <Eigen/Core>  // before OpenCV's Eigen utilities
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "map/camera_model.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "matching/matcher.hpp"
#include "optimize/pnp_pose.hpp"
#include "optimize/pose_optimizer.hpp"

namespace beslam::orb {
namespace {

// Pose-only optimisation of the frame's matches; outliers are flagged. Returns the inliers.
int optimize(Frame& frame, const Camera& camera, const ScalePyramid& pyramid, double trusted_weight) {
  std::vector<optimize::PoseObservation> obs;
  std::vector<size_t> idx;
  for (size_t i = 0; i < frame.size(); ++i) {
    const MapPoint* mp = frame.points[i];
    if (!mp) continue;
    const cv::KeyPoint& kp = frame.features->keypoints[i];
    double inv_sigma = pyramid.inv_scale[kp.octave];
    if (mp->trusted) inv_sigma *= std::sqrt(trusted_weight);
    obs.push_back({mp->position, Eigen::Vector2d(kp.pt.x, kp.pt.y), inv_sigma});
    idx.push_back(i);
  }
  std::vector<bool> outlier;
  const int inliers = optimize::optimizePose(camera, obs, frame.T_cw, outlier);
  for (size_t k = 0; k < idx.size(); ++k) frame.outlier[idx[k]] = outlier[k];
  return inliers;
}

void dropOutliers(Frame& frame) {
  for (size_t i = 0; i < frame.size(); ++i)
    if (frame.outlier[i]) {
      frame.points[i] = nullptr;
      frame.outlier[i] = false;
    }
}

// The points of the candidate's neighbourhood, each once, in id order.
std::vector<MapPoint*> neighbourhoodPoints(const KeyFrame* kf) {
  std::vector<KeyFrame*> kfs = kf->bestCovisibles(10);
  kfs.push_back(const_cast<KeyFrame*>(kf));
  std::vector<MapPoint*> points;
  for (const KeyFrame* k : kfs)
    for (MapPoint* mp : k->points)
      if (mp && !mp->bad) points.push_back(mp);
  std::sort(points.begin(), points.end(), IdLess<MapPoint>());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  return points;
}

bool tryCandidate(Frame& frame, const KeyFrame* kf, const Camera& camera, const ScalePyramid& pyramid,
                  const MapLocaliserOptions& o) {
  const std::vector<MapPoint*> points = neighbourhoodPoints(kf);
  frame.clearMatches();
  if (matching::searchByProjectionWide(frame, points, kf->T_cw, camera, pyramid, o.radius, 0.75f, matching::kThLow) <
      o.min_matches)
    return false;
  if (poseFromMatches(frame, camera, {o.seed, 4.0f, o.min_matches, false}) < 0) return false;
  optimize(frame, camera, pyramid, o.trusted_weight);
  dropOutliers(frame);
  // With the pose found, a narrow search brings in the neighbourhood's other points.
  frame.clearMatches();
  matching::searchByProjectionWide(frame, points, frame.T_cw, camera, pyramid, 10.f, 0.9f, matching::kThHigh);
  const int n = optimize(frame, camera, pyramid, o.trusted_weight);
  dropOutliers(frame);
  return n >= o.min_inliers;
}

}  // namespace

std::vector<KeyFrame*> candidatesByFrameOrder(const Map& map, int64_t frame_index) {
  std::vector<KeyFrame*> kfs(map.keyframes().begin(), map.keyframes().end());
  std::stable_sort(kfs.begin(), kfs.end(), [frame_index](const KeyFrame* a, const KeyFrame* b) {
    return std::llabs(a->frame_index - frame_index) < std::llabs(b->frame_index - frame_index);
  });
  return kfs;
}

KeyFrame* localiseInMap(Frame& frame, const std::vector<KeyFrame*>& candidates, const Camera& camera,
                        const ScalePyramid& pyramid, const MapLocaliserOptions& options) {
  for (KeyFrame* kf : candidates) {
    if (!kf || kf->bad) continue;
    if (tryCandidate(frame, kf, camera, pyramid, options)) {
      frame.has_pose = true;
      frame.reference = kf;
      return kf;
    }
  }
  frame.clearMatches();
  return nullptr;
}

}  // namespace beslam::orb
