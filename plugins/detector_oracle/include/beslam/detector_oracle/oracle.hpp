// The label oracle: ground-truth boxes (KITTI or synthetic tracking labels) made into a detector with
// controlled faults, for ablations: position noise (isotropic, plus depth noise along the viewing ray
// growing with range, as a monocular detector's), relative size noise, yaw noise, missed detections,
// false positives and scores. Every random draw of frame f comes from a generator seeded with
// (seed, f) only (splitmix64 -> std::mt19937_64, with the oracle's own uniform / normal / Poisson
// transforms), so a frame's boxes are the same on every platform and whatever frames were asked before.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "beslam/data.h"

namespace beslam::detector_oracle {

// Deterministic random numbers from std::mt19937_64 (whose output sequence the standard fixes).
class Random {
 public:
  explicit Random(uint64_t seed) : engine_(seed) {}
  double uniform();  // [0, 1)
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  double normal();                                      // N(0, 1), Box-Muller
  int poisson(double mean);                             // Knuth's method (mean <= ~50)
  static uint64_t mix(uint64_t seed, uint64_t stream);  // splitmix64 of seed and stream

 private:
  std::mt19937_64 engine_;
  bool have_spare_ = false;
  double spare_ = 0;
};

struct OracleOptions {
  std::vector<int32_t> classes;    // BESLAM_CLASS_* kept; empty: all
  double position_noise = 0.0;     // m, std dev of each centre coordinate
  double depth_noise_per_m = 0.0;  // std dev along the viewing ray, as a fraction of the range
  double size_noise = 0.0;         // relative std dev of l, w, h (size * (1 + n), floored at 10 %)
  double yaw_noise = 0.0;          // rad
  double miss_rate = 0.0;          // probability a true box is dropped
  double false_positives = 0.0;    // mean false boxes per frame (Poisson)
  double max_range = 80.0;         // m: labels farther away are not detected; false positives fall inside
  double true_score_min = 0.6, false_score_max = 0.9;  // true boxes score U(min, 1), false ones U(0.3, max)
  uint64_t seed = 0;
  bool pass_track_ids = false;  // keep the label's track id (default -1: the motion checker must track)
};

// One ground-truth object of one frame.
struct TruthBox {
  beslam_box3d box;  // geometric centre, l w h, yaw; track_id = the label's; motion_state if known
};

class LabelOracle {
 public:
  LabelOracle(std::vector<std::vector<TruthBox>> frames, const OracleOptions& options);
  // The frame's detections (throws std::out_of_range for a frame past the labels: see lastFrame()).
  std::vector<beslam_box3d> detect(int64_t frame) const;
  int64_t lastFrame() const { return static_cast<int64_t>(frames_.size()) - 1; }

 private:
  std::vector<std::vector<TruthBox>> frames_;
  OracleOptions o_;
};

// Reads a tracking label file (label_02/SSSS.txt, KITTI or `beslam synth`): frame -> boxes of the known
// classes (DontCare skipped; an unknown class or a malformed row throws "file:line: ..."). With a
// motion file (objects_motion.txt: "frame track_id moving speed"), motion_state is set to STATIC /
// DYNAMIC from it; a label without a motion row stays UNKNOWN.
std::vector<std::vector<TruthBox>> readTruth(const std::string& labels, const std::string& motion = "");

}  // namespace beslam::detector_oracle
