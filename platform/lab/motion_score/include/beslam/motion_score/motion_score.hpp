// Scores the motion states a pipeline run wrote (objects.txt) against the truth of a synthetic sequence
// (label_02 boxes and objects_motion.txt), and counts states by range on any run.
//
// Matching: per frame, each detection goes to the nearest unclaimed label of a car-like class (Car, Van,
// Truck) by BEV distance of the bottom centres (camera frame), within match_distance. Truth: the label's
// (frame, track id) row of objects_motion.txt: moving or standing. 'dynamic' is the positive class:
// TP = moving called dynamic, FN = moving called static or unknown, FP = standing called dynamic.
// Range is the label's horizontal distance from the camera.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace beslam::motion_score {

struct Options {
  double match_distance = 2.0;  // m, BEV
  double max_range = 1e9;       // m: labels farther away are not scored
  double static_range = 30.0;   // m: the "parked cars called static" share counts labels within this
};

struct Counts {
  int64_t detections = 0, matched = 0;
  int64_t tp = 0, fp = 0, fn = 0;
  int64_t moving = 0, moving_static = 0, moving_unknown = 0;
  int64_t standing = 0, standing_dynamic = 0, standing_unknown = 0;
  int64_t standing_near = 0, standing_near_static = 0;  // within static_range
  double f1() const;
  double movingCalledStatic() const { return moving ? double(moving_static) / double(moving) : 0.0; }
  double standingCalledDynamic() const { return standing ? double(standing_dynamic) / double(standing) : 0.0; }
  double standingNearCalledStatic() const {
    return standing_near ? double(standing_near_static) / double(standing_near) : 0.0;
  }
};

// objects_path: a run's objects.txt; labels_path: label_02 rows; motion_path: objects_motion.txt.
// Throws beslam::Error naming the file on a missing or malformed file.
Counts score(const std::string& objects_path, const std::string& labels_path, const std::string& motion_path,
             const Options& options);

// `beslam eval-motion`: see its --help.
int runCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace beslam::motion_score
