// The motion benchmark on KITTI tracking: replayed detections (AB3DMOT rows, e.g. PointRCNN), ego poses
// (KITTI format, T_world_cam2), the BEV tracker, scored against label_02.
//
// Truth: every labelled car (Car and Van) is moved into the world frame with the ego pose of its frame
// (geometric box centre); its world speed at frame t is the BEV distance between its positions at the
// first and last frames it has within [t - half_window, t + half_window], over that time (the span must
// be at least min_span frames). Moving above moving_speed, parked below parked_speed, in between (or
// with too short a span) not scored. Per frame, Car detections are matched to labelled cars (Hungarian on
// BEV centre distance in the camera frame, gated at match_distance). A matched pair is scored when the
// label is within max_range of the camera and its track is past its first `warmup` frames.
// 'dynamic' is the positive class: TP = moving called dynamic, FN = moving called static or unknown,
// FP = parked called dynamic.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "beslam/motion/bev_tracker.hpp"

namespace beslam::motion {

struct EvalOptions {
  std::string root;  // .../kitti/tracking/training
  std::string detections = "det_pointrcnn";
  std::string poses = "ego_poses_orbslam3";
  std::string labels = "label_02";
  double min_score = 0.8;  // on sigmoid(PointRCNN logit), as configs/kitti_tracking_motion.yaml
  Params params;
  double moving_speed = 1.0, parked_speed = 0.3;
  int half_window = 5, min_span = 6;
  double frame_dt = 0.1;
  double match_distance = 2.0;
  double max_range = 40.0;
  int warmup = 3;
  std::ostream* trace = nullptr;  // when set: one line per wrongly called scored pair
};

struct EvalCounts {
  int64_t frames = 0, boxes = 0;
  int64_t tp = 0, fp = 0, fn = 0;
  int64_t moving = 0, moving_static = 0, moving_unknown = 0;
  int64_t parked = 0, parked_dynamic = 0, parked_unknown = 0;
  int64_t labels_scorable = 0, labels_matched = 0;  // truth-scored labels in range past warm-up / with a detection
  std::vector<double> frame_ms;                     // tracker time per frame

  void add(const EvalCounts& o);
  double precision() const { return tp + fp ? double(tp) / double(tp + fp) : 0.0; }
  double recall() const { return tp + fn ? double(tp) / double(tp + fn) : 0.0; }
  double f1() const {
    const double p = precision(), r = recall();
    return p + r > 0 ? 2 * p * r / (p + r) : 0.0;
  }
  double movingCalledStatic() const { return moving ? double(moving_static) / double(moving) : 0.0; }
  double parkedCalledDynamic() const { return parked ? double(parked_dynamic) / double(parked) : 0.0; }
  double medianMs() const;
  double meanMs() const;
};

// One sequence's inputs, read once (detections, poses, labels and their world tracks) so that many tracker
// settings can be evaluated on it without reading the files again (motion_bench --loo).
struct SequenceData;
struct SequenceDataDeleter {
  void operator()(SequenceData* d) const;
};
using SequenceDataPtr = std::unique_ptr<SequenceData, SequenceDataDeleter>;

// Reads one sequence ("0007") as `options` name it; throws std::runtime_error naming a missing or malformed file.
SequenceDataPtr loadSequence(const EvalOptions& options, const std::string& sequence);
// Runs the tracker with options.params over loaded data and scores it (the reading options are not used again).
EvalCounts evaluateLoaded(const EvalOptions& options, const SequenceData& data);
// loadSequence + evaluateLoaded.
EvalCounts evaluateSequence(const EvalOptions& options, const std::string& sequence);

}  // namespace beslam::motion
