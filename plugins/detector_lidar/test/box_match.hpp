// Scoring helpers shared by the detector_lidar tests and its evaluation tool: KITTI labels as ABI boxes
// (geometric centre) and greedy nearest-centre matching in the bird's-eye view.
#pragma once

#include <cstddef>
#include <vector>

#include "beslam/data.h"
#include "beslam/formats/labels.hpp"

namespace beslam::detector_lidar::eval {

// A label as an ABI box: centre lifted from KITTI's bottom centre by half the height.
beslam_box3d labelToBox(const formats::ObjectLabel& label, int32_t class_id);

// BEV (x, z) distance between two box centres.
double bevDistance(const beslam_box3d& a, const beslam_box3d& b);

struct Match {
  std::size_t truth = 0;
  int detection = -1;  // index into detections, -1: none within max_distance
  double error = 0;    // BEV centre distance (m) when matched
};

// Greedy one-to-one matching, closest pairs first, pairs farther than max_distance left unmatched.
std::vector<Match> matchBev(const std::vector<beslam_box3d>& truth, const std::vector<beslam_box3d>& detections,
                            double max_distance);

}  // namespace beslam::detector_lidar::eval
