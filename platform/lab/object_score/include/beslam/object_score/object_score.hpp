// Scores the objects a run reconstructed (objects.json, objects/*.ply) against the truth of a synthetic
// sequence: the paper's Table II count and the pose and shape errors of issue 15.
//
// Truth (beslam synth output, SEQ = OUT/sequences/NN): objects/objects.txt (type, behaviour, size),
// objects/poses.txt (T_world_obj per frame, KITTI object frame: x fwd, y down, z left, origin at the
// bottom centre), objects/car_TTTT.ply, objects_motion.txt, label_02/NN.txt (what is in view), and the
// camera poses OUT/poses/NN.txt. A run's objects live in its own world (landmark frame: x heading, y left,
// z up, origin at the centre).
//
// Local alignment: an object is carried into the truth world through the run's camera nearest to it:
// T_true_obj = T_true_cam(f) * T_run_cam(f)^-1 * T_run_obj, with f the tracked frame whose camera centre
// is nearest the object. This scores the object against the map around it, not the trajectory's drift.
//
// Counting (Table II): "parked" = a car (Car or Van) that stands in every frame. In view = labelled in a
// tracked frame within `view_range` (horizontal distance from the camera). A reconstruction is matched
// to the nearest car of any behaviour by centre distance (within `match_distance`) at frame f; it is
// correct when that car is parked, the centre error is within `centre_tolerance` and the heading error
// within `yaw_tolerance`; false when no car is within `match_distance` or the car is moving at f.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace beslam::object_score {

struct Options {
  double view_range = 15.0;         // m: parked cars counted in the denominator
  double match_distance = 2.5;      // m: a reconstruction farther from every car is false ("no car")
  double centre_tolerance = 1.0;    // m
  double yaw_tolerance_deg = 20.0;  // degrees, heading (front and back differ)
  int chamfer_samples = 2000;       // surface samples per mesh (seeded)
};

struct ObjectResult {
  int32_t track_id = -1;        // the run's
  int32_t truth_track_id = -1;  // matched truth car (-1: none)
  bool parked = false, moving = false, correct = false;
  double centre_error_m = -1, yaw_error_deg = -1;
  // Symmetric mean over surface samples, both meshes in the truth world (pose error included); the true
  // mesh's samples are on its exterior only (faces buried in another part, a wheel rim in the body, are
  // not what a sensor or a reconstruction can see).
  double chamfer_m = -1;
  double shape_chamfer_m = -1;  // the same with the reconstruction moved onto the true pose (shape alone)
  int keyframes = 0;
};

struct Score {
  int64_t reconstructed = 0;                          // objects in objects.json
  int64_t correct = 0, false_objects = 0, other = 0;  // other: matched a car that stands but is not parked
  int64_t parked_in_view = 0;                         // the denominator: parked cars in view within view_range
  int64_t parked_in_view_correct = 0;                 // of those, reconstructed correctly
  std::vector<ObjectResult> objects;
  double correctShare() const { return parked_in_view ? double(parked_in_view_correct) / double(parked_in_view) : 0; }
  double falseShare() const { return reconstructed ? double(false_objects) / double(reconstructed) : 0; }
};

// run_dir: a run folder (summary.json, objects.json, trajectory.tum). Throws beslam::Error naming the
// file on a missing or malformed file.
Score score(const std::string& run_dir, const Options& options);

// `beslam eval-objects`: see its --help.
int runCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace beslam::object_score
