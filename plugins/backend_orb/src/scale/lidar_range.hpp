// LiDAR ranges of keypoints: where a frame has a scan (and the rig its LiDAR-to-camera extrinsics), the
// metric distance from the camera to the surface under each keypoint. They give the monocular map its
// scale and, once metric, hold it in local BA (optimize::ObjectRangeCost); docs/metric-scale.md.
//
// A keypoint takes the depth of the scan's return that projects nearest it, within a small window that must see
// one surface: when the nearest and farthest return in it differ by more than max_depth_spread of the
// nearest (an object's edge, a return the camera cannot see from its own viewpoint), the keypoint gets none.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "beslam_orb/options.hpp"

namespace beslam::orb {

struct FeatureSet;

struct LidarRangeOptions {
  int half_width = 2;              // pixels left and right of the keypoint (a 64-beam scan: ~2.5 px apart)
  int half_height = 3;             // pixels above and below (its rows: ~5 px apart at KITTI's focal length)
  double max_depth_spread = 0.05;  // of the nearest return's depth
  double min_depth = 1.0;          // metres: returns nearer the camera are the ego car's own body
};

// p_cam: the scan's points in the camera frame (x right, y down, z forward, metres). Fills
// features.lidar_range (one entry per keypoint, 0 where there is no clear range).
void setLidarRanges(FeatureSet& features, const Eigen::Matrix3Xf& p_cam, const Camera& camera,
                    const LidarRangeOptions& options = {});

}  // namespace beslam::orb
