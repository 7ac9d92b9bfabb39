// A frame's pose from its 2D-3D matches (frame.points) with OpenCV's PnP in RANSAC, seeded: the matches
// that are not RANSAC inliers are dropped from the frame and frame.T_cw is set. Used by relocalisation
// (bag of words or around the last pose) and by the first localisation in a loaded map.
#pragma once

#include <cstdint>

#include "beslam_orb/options.hpp"

namespace beslam::orb {

struct Frame;

struct PnpOptions {
  uint64_t seed = 0;
  float threshold_px = 4.0f;  // RANSAC reprojection threshold
  int min_inliers = 10;
  bool epnp = false;  // the EPnP solver (else OpenCV's default, iterative)
};

// The number of inliers, or -1 when RANSAC fails or finds fewer than min_inliers (the frame unchanged then).
int poseFromMatches(Frame& frame, const Camera& camera, const PnpOptions& options);

}  // namespace beslam::orb
