#include "kitti_motion_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "beslam/detector_replay/replay.hpp"
#include "beslam/formats/labels.hpp"
#include "beslam/formats/trajectory.hpp"
#include "beslam/motion/hungarian.hpp"

namespace beslam::motion {

namespace fs = std::filesystem;

void EvalCounts::add(const EvalCounts& o) {
  frames += o.frames, boxes += o.boxes, tp += o.tp, fp += o.fp, fn += o.fn;
  moving += o.moving, moving_static += o.moving_static, moving_unknown += o.moving_unknown;
  parked += o.parked, parked_dynamic += o.parked_dynamic, parked_unknown += o.parked_unknown;
  labels_scorable += o.labels_scorable, labels_matched += o.labels_matched;
  frame_ms.insert(frame_ms.end(), o.frame_ms.begin(), o.frame_ms.end());
}

double EvalCounts::medianMs() const {
  if (frame_ms.empty()) return 0;
  std::vector<double> v = frame_ms;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

double EvalCounts::meanMs() const {
  double s = 0;
  for (double v : frame_ms) s += v;
  return frame_ms.empty() ? 0 : s / static_cast<double>(frame_ms.size());
}

namespace {

struct LabelBox {
  int64_t track_id;
  Eigen::Vector3d center_cam;  // geometric centre
};

enum class Truth { moving, parked, unscored };

}  // namespace

struct SequenceData {
  std::string seq;
  formats::Trajectory poses;
  detector_replay::DetectionTable table;
  std::vector<std::vector<LabelBox>> frame_labels;
  std::map<int64_t, std::map<int64_t, Eigen::Vector2d>> track_world;  // track -> frame -> BEV
  std::map<int64_t, int64_t> first_frame;
};

void SequenceDataDeleter::operator()(SequenceData* d) const { delete d; }

SequenceDataPtr loadSequence(const EvalOptions& o, const std::string& seq) {
  using namespace beslam::detector_replay;
  const fs::path root(o.root);
  SequenceDataPtr data(new SequenceData);
  data->seq = seq;
  data->poses = formats::readKitti((root / o.poses / (seq + ".txt")).string());
  const formats::Trajectory& poses = data->poses;

  // Detections: every class file present (the tracker sees pedestrians and cyclists too, as in a pipeline).
  DetectionTable& table = data->table;
  Report report;
  Filter filter;
  filter.min_score = o.min_score;
  int files = 0;
  for (const char* cls : {"Car", "Pedestrian", "Cyclist"}) {
    const fs::path file = root / o.detections / cls / (seq + ".txt");
    if (!fs::exists(file)) continue;
    readAb3dmotFile(file.string(), filter, Policy::stop, ScoreTransform::sigmoid, table, report);
    ++files;
  }
  if (files == 0) throw std::runtime_error((root / o.detections).string() + ": no detection files for sequence " + seq);

  // Labels: cars (Car, Van) per frame, and each track's world BEV position per frame.
  const std::vector<formats::TrackingLabel> labels =
      formats::readTrackingLabels((root / o.labels / (seq + ".txt")).string());
  const int64_t n_frames = static_cast<int64_t>(poses.size());
  auto& frame_labels = data->frame_labels;
  frame_labels.resize(static_cast<size_t>(n_frames));
  auto& track_world = data->track_world;
  for (const auto& l : labels) {
    if (l.object.type != "Car" && l.object.type != "Van") continue;
    if (l.frame < 0 || l.frame >= n_frames) continue;
    const Eigen::Vector3d c = l.object.p_cam_bottom - Eigen::Vector3d(0, l.object.h / 2, 0);
    frame_labels[static_cast<size_t>(l.frame)].push_back({l.track_id, c});
    const Eigen::Vector3d w = poses.poses[static_cast<size_t>(l.frame)] * c;
    track_world[l.track_id][l.frame] = Eigen::Vector2d(w.x(), w.z());
  }
  for (const auto& [track, frames] : track_world) data->first_frame[track] = frames.begin()->first;
  return data;
}

EvalCounts evaluateLoaded(const EvalOptions& o, const SequenceData& data) {
  const std::string& seq = data.seq;
  const formats::Trajectory& poses = data.poses;
  const detector_replay::DetectionTable& table = data.table;
  const auto& frame_labels = data.frame_labels;
  const auto& track_world = data.track_world;
  const auto& first_frame = data.first_frame;
  const int64_t n_frames = static_cast<int64_t>(poses.size());
  double truth_speed = 0;
  auto truthAt = [&](int64_t track, int64_t frame) {
    const auto& m = track_world.at(track);
    auto a = m.lower_bound(frame - o.half_window);
    auto b = m.upper_bound(frame + o.half_window);
    if (a == m.end() || b == m.begin()) return Truth::unscored;
    --b;
    if (b->first - a->first < o.min_span) return Truth::unscored;
    const double speed = (b->second - a->second).norm() / (static_cast<double>(b->first - a->first) * o.frame_dt);
    truth_speed = speed;
    if (speed > o.moving_speed) return Truth::moving;
    if (speed < o.parked_speed) return Truth::parked;
    return Truth::unscored;
  };

  BevTracker tracker(o.params);
  EvalCounts c;
  for (int64_t f = 0; f < n_frames; ++f) {
    std::vector<beslam_box3d> boxes = table.at(f);
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<Decision> decisions =
        tracker.update(static_cast<double>(f) * o.frame_dt, poses.poses[static_cast<size_t>(f)], boxes);
    for (size_t i = 0; i < boxes.size(); ++i)
      boxes[i].track_id = decisions[i].track_id, boxes[i].motion_state = decisions[i].motion_state;
    c.frame_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    ++c.frames;
    c.boxes += static_cast<int64_t>(boxes.size());

    // Match Car detections to labelled cars.
    std::vector<size_t> cars;
    for (size_t i = 0; i < boxes.size(); ++i)
      if (boxes[i].class_id == BESLAM_CLASS_CAR) cars.push_back(i);
    const auto& gt = frame_labels[static_cast<size_t>(f)];
    std::vector<int> label_to_det(gt.size(), -1);
    if (!gt.empty() && !cars.empty()) {
      const double kFar = 1e6;
      std::vector<double> cost(gt.size() * cars.size(), kFar);
      for (size_t g = 0; g < gt.size(); ++g)
        for (size_t k = 0; k < cars.size(); ++k) {
          const beslam_box3d& b = boxes[cars[k]];
          const double d = std::hypot(b.center_cam[0] - gt[g].center_cam.x(), b.center_cam[2] - gt[g].center_cam.z());
          if (d <= o.match_distance) cost[g * cars.size() + k] = d;
        }
      const std::vector<int> a = solveAssignment(cost, static_cast<int>(gt.size()), static_cast<int>(cars.size()));
      for (size_t g = 0; g < gt.size(); ++g)
        if (a[g] >= 0 && cost[g * cars.size() + static_cast<size_t>(a[g])] < kFar)
          label_to_det[g] = static_cast<int>(cars[static_cast<size_t>(a[g])]);
    }
    for (size_t g = 0; g < gt.size(); ++g) {
      const LabelBox& l = gt[g];
      if (std::hypot(l.center_cam.x(), l.center_cam.z()) > o.max_range) continue;
      if (f - first_frame.at(l.track_id) < o.warmup) continue;
      const Truth truth = truthAt(l.track_id, f);
      if (truth == Truth::unscored) continue;
      ++c.labels_scorable;
      if (label_to_det[g] < 0) continue;
      ++c.labels_matched;
      const int32_t state = boxes[static_cast<size_t>(label_to_det[g])].motion_state;
      if (o.trace && ((truth == Truth::moving && state != BESLAM_MOTION_DYNAMIC) ||
                      (truth == Truth::parked && state == BESLAM_MOTION_DYNAMIC))) {
        const Decision& d = decisions[static_cast<size_t>(label_to_det[g])];
        *o.trace << seq << " frame " << f << " label " << l.track_id << " truth "
                 << (truth == Truth::moving ? "moving" : "parked") << " " << truth_speed << " m/s, called " << state
                 << " track " << d.track_id << " speed " << d.speed << " +- " << d.speed_sigma << " range " << d.range
                 << "\n";
      }
      if (truth == Truth::moving) {
        ++c.moving;
        if (state == BESLAM_MOTION_DYNAMIC)
          ++c.tp;
        else
          ++c.fn;
        if (state == BESLAM_MOTION_STATIC) ++c.moving_static;
        if (state == BESLAM_MOTION_UNKNOWN) ++c.moving_unknown;
      } else {
        ++c.parked;
        if (state == BESLAM_MOTION_DYNAMIC) ++c.fp, ++c.parked_dynamic;
        if (state == BESLAM_MOTION_UNKNOWN) ++c.parked_unknown;
      }
    }
  }
  return c;
}

EvalCounts evaluateSequence(const EvalOptions& o, const std::string& seq) {
  return evaluateLoaded(o, *loadSequence(o, seq));
}

}  // namespace beslam::motion
