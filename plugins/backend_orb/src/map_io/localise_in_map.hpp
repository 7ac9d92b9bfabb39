// Localising a frame in a map without a pose of its own to start from (a loaded map, before the first
// pose): each candidate keyframe's pose is tried as the prior. The map points seen by the candidate and
// its best covisible keyframes are searched by projection in a wide window, a seeded PnP RANSAC and
// pose-only optimisation follow, then a narrow search with that pose and a second optimisation; the
// first candidate with at least min_inliers pose inliers (ORB-SLAM2's relocalisation rule: 50) wins.
// The candidates come from the caller: keyframes by frame order today, place-recognition (bag of words)
// candidates once there is a vocabulary.
#pragma once

#include <cstdint>
#include <vector>

#include "beslam_orb/options.hpp"
#include "features/scale_pyramid.hpp"
#include "map/map_fwd.hpp"

namespace beslam::orb {

struct MapLocaliserOptions {
  float radius = 60.f;          // px at level 0: wide search around the candidate's projection
  int min_matches = 30;         // matches needed before PnP
  int min_inliers = 50;         // pose inliers to accept
  double trusted_weight = 1.0;  // Options::static_object_weight
  uint64_t seed = 42;           // PnP RANSAC
};

// Every live keyframe, nearest in frame index to `frame_index` first (ties: smaller id first).
std::vector<KeyFrame*> candidatesByFrameOrder(const Map& map, int64_t frame_index);

// Tries the candidates in order. On success the frame has the pose (T_cw, has_pose) and its inlier
// matches (points, no outliers) and the candidate is returned; otherwise null and no matches.
KeyFrame* localiseInMap(Frame& frame, const std::vector<KeyFrame*>& candidates, const Camera& camera,
                        const ScalePyramid& pyramid, const MapLocaliserOptions& options);

}  // namespace beslam::orb
