#include "beslam/detector_oracle/oracle.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "beslam/detector_replay/replay.hpp"
#include "beslam/formats/labels.hpp"

namespace beslam::detector_oracle {

uint64_t Random::mix(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double Random::uniform() { return static_cast<double>(engine_() >> 11) * (1.0 / 9007199254740992.0); }

double Random::normal() {
  if (have_spare_) {
    have_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - uniform();  // (0, 1]
  const double u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = 2.0 * 3.14159265358979323846 * u2;
  spare_ = r * std::sin(a);
  have_spare_ = true;
  return r * std::cos(a);
}

int Random::poisson(double mean) {
  if (mean <= 0) return 0;
  const double limit = std::exp(-mean);
  int k = 0;
  double p = uniform();
  while (p > limit && k < 1000) {
    ++k;
    p *= uniform();
  }
  return k;
}

LabelOracle::LabelOracle(std::vector<std::vector<TruthBox>> frames, const OracleOptions& options)
    : frames_(std::move(frames)), o_(options) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("label oracle: " + what); };
  if (!(o_.position_noise >= 0) || !(o_.depth_noise_per_m >= 0) || !(o_.size_noise >= 0) || !(o_.yaw_noise >= 0))
    bad("noise levels must be >= 0");
  if (!(o_.miss_rate >= 0 && o_.miss_rate <= 1)) bad("miss_rate must be in [0, 1]");
  if (!(o_.false_positives >= 0 && o_.false_positives <= 50)) bad("false_positives must be in [0, 50]");
  if (!(o_.max_range > 5)) bad("max_range must be > 5 m");
}

std::vector<beslam_box3d> LabelOracle::detect(int64_t frame) const {
  if (frame < 0 || frame > lastFrame())
    throw std::out_of_range("frame " + std::to_string(frame) + " is past the labels (last frame " +
                            std::to_string(lastFrame()) + ")");
  Random rng(Random::mix(o_.seed, static_cast<uint64_t>(frame)));
  std::vector<beslam_box3d> out;
  for (const TruthBox& t : frames_[static_cast<size_t>(frame)]) {
    // Draw every number for every label, kept or not, so one object's faults do not shift another's.
    const double miss = rng.uniform();
    const double n[8] = {rng.normal(), rng.normal(), rng.normal(), rng.normal(),
                         rng.normal(), rng.normal(), rng.normal(), rng.normal()};
    const double score = rng.uniform(o_.true_score_min, 1.0);
    beslam_box3d b = t.box;
    if (!o_.classes.empty() && std::find(o_.classes.begin(), o_.classes.end(), b.class_id) == o_.classes.end())
      continue;
    const double range = std::hypot(b.center_cam[0], b.center_cam[2]);
    if (range > o_.max_range || b.center_cam[2] <= 0.5) continue;
    if (miss < o_.miss_rate) continue;
    const double ray[3] = {b.center_cam[0] / range, 0.0, b.center_cam[2] / range};
    for (int k = 0; k < 3; ++k)
      b.center_cam[k] += o_.position_noise * n[k] + o_.depth_noise_per_m * range * n[3] * ray[k];
    for (int k = 0; k < 3; ++k) b.size[k] *= std::max(0.1, 1.0 + o_.size_noise * n[4 + k]);
    b.yaw = std::remainder(b.yaw + o_.yaw_noise * n[7], 2 * 3.14159265358979323846);
    b.score = static_cast<float>(score);
    if (!o_.pass_track_ids) b.track_id = -1;
    out.push_back(b);
  }
  const int false_count = rng.poisson(o_.false_positives);
  for (int i = 0; i < false_count; ++i) {
    beslam_box3d b{};
    b.track_id = -1;
    b.motion_state = BESLAM_MOTION_UNKNOWN;
    b.class_id = o_.classes.empty() ? BESLAM_CLASS_CAR : o_.classes.front();
    const bool person = b.class_id == BESLAM_CLASS_PEDESTRIAN || b.class_id == BESLAM_CLASS_CYCLIST;
    b.size[0] = person ? 0.8 : rng.uniform(3.5, 5.0);
    b.size[1] = person ? 0.6 : rng.uniform(1.5, 2.0);
    b.size[2] = person ? 1.7 : rng.uniform(1.4, 1.9);
    const double z = rng.uniform(3.0, o_.max_range), x = rng.uniform(-0.6, 0.6) * z;
    b.center_cam[0] = x;
    b.center_cam[1] = 1.65 - b.size[2] / 2;  // on a road 1.65 m below the camera
    b.center_cam[2] = z;
    b.yaw = rng.uniform(-3.14159265358979323846, 3.14159265358979323846);
    b.score = static_cast<float>(rng.uniform(0.3, o_.false_score_max));
    out.push_back(b);
  }
  return out;
}

std::vector<std::vector<TruthBox>> readTruth(const std::string& labels, const std::string& motion) {
  std::map<std::pair<int64_t, int64_t>, bool> moving;
  if (!motion.empty()) moving = formats::readObjectMotion(motion);
  std::vector<std::vector<TruthBox>> frames;
  detector_replay::forEachLine(labels, "label file", [&](const std::string& line, int line_no) {
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') return;
    const formats::TrackingLabel l = formats::parseTrackingRow(line, labels, line_no);
    if (l.frame < 0 || l.frame > 10'000'000)
      throw std::runtime_error(labels + ":" + std::to_string(line_no) + ": frame " + std::to_string(l.frame) +
                               " is out of range");
    if (static_cast<size_t>(l.frame) >= frames.size()) frames.resize(static_cast<size_t>(l.frame) + 1);
    if (l.object.isDontCare()) return;
    int32_t class_id = 0;
    if (!detector_replay::kittiClass(l.object.type, class_id))
      throw std::runtime_error(labels + ":" + std::to_string(line_no) + ": unknown class '" + l.object.type + "'");
    const auto& o = l.object;
    if (!(o.h > 0 && o.w > 0 && o.l > 0))
      throw std::runtime_error(labels + ":" + std::to_string(line_no) + ": non-positive box size");
    TruthBox t;
    t.box = detector_replay::boxFromKitti(class_id, o.h, o.w, o.l, o.p_cam_bottom.x(), o.p_cam_bottom.y(),
                                          o.p_cam_bottom.z(), o.ry);
    t.box.track_id = static_cast<int32_t>(l.track_id);
    t.box.bbox2d[0] = o.x1, t.box.bbox2d[1] = o.y1, t.box.bbox2d[2] = o.x2, t.box.bbox2d[3] = o.y2;
    t.box.truncation = static_cast<float>(std::clamp(o.truncated, 0.0, 1.0));
    t.box.occlusion = o.occluded;
    if (auto it = moving.find({l.frame, l.track_id}); it != moving.end())
      t.box.motion_state = it->second ? BESLAM_MOTION_DYNAMIC : BESLAM_MOTION_STATIC;
    frames[static_cast<size_t>(l.frame)].push_back(t);
  });
  if (frames.empty()) throw std::runtime_error(labels + ": no labels");
  return frames;
}

}  // namespace beslam::detector_oracle
