// backend_pose_replay: a backend that replays camera poses from a file instead of estimating them.
// It lets the semantic plugins (detector, motion checker, masks, reconstructor) run on ground truth or
// on an external odometry, and is how the motion benchmark runs. KITTI files are matched to frames by
// row = frame index; TUM files by nearest timestamp within max_time_diff. A frame with no pose is
// reported LOST and left out of the trajectories, never invented. Every keyframe_interval-th tracked
// frame is declared a keyframe so a reconstructor downstream gets work.
#include <algorithm>
#include <cmath>

#include "backend_pose_replay_settings.hpp"  // Options and kSettings, from settings.json
#include "beslam/formats/trajectory.hpp"
#include "beslam/sdk/sdk.hpp"

namespace {

using beslam::sdk::TrajectoryEntry;

const beslam::sdk::PluginInfo kInfo("backend_pose_replay", "Pose replay",
                                    "Replays camera poses from a KITTI or TUM file (ground truth or external odometry)",
                                    {1, 0, 0}, kSettings);

struct PoseFile {
  bool timestamped = false;  // TUM: match by time; KITTI: row = frame index
  beslam::formats::Trajectory poses;
};

PoseFile readPoses(const std::string& path, const std::string& format) {
  PoseFile file;
  const std::string used = format == "auto" ? beslam::formats::detectFormat(path) : format;
  file.poses = beslam::formats::read(path, used);
  file.timestamped = used == "tum";
  if (file.timestamped)
    for (size_t i = 1; i < file.poses.size(); ++i)
      if (!(file.poses.stamps[i] > file.poses.stamps[i - 1]))
        throw std::runtime_error(path + ": timestamps must increase (pose " + std::to_string(i + 1) + ")");
  return file;
}

class PoseReplay : public beslam::sdk::Backend {
 public:
  PoseReplay(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : options_(kSettings.read(config)), file_(readPoses(options_.poses, options_.format)) {
    context.info("replaying " + std::to_string(file_.poses.size()) + " poses from " + options_.poses);
  }

  std::optional<Eigen::Isometry3d> predictPose(const beslam::sdk::Frame& frame) override {
    const long i = lookup(frame);
    if (i < 0) return std::nullopt;
    return file_.poses.poses[i];
  }

  beslam::sdk::TrackResult track(const beslam::sdk::Frame& frame, const cv::Mat&,
                                 const std::vector<beslam_box3d>&) override {
    beslam::sdk::TrackResult result;
    result.world_is_metric = options_.metric && frame.index >= options_.metric_from_frame;
    const long i = lookup(frame);
    if (i < 0) {
      result.state = tracked_.empty() ? BESLAM_TRACKING_NOT_INITIALIZED : BESLAM_TRACKING_LOST;
      return result;
    }
    result.state = BESLAM_TRACKING_OK;
    result.T_world_cam = file_.poses.poses[i];
    const TrajectoryEntry entry{frame.index, frame.timestamp, file_.poses.poses[i]};
    if (static_cast<int64_t>(tracked_.size()) % options_.keyframe_interval == 0) {
      result.is_keyframe = true;
      result.keyframe_id = static_cast<int64_t>(keyframes_.size());
      keyframes_.push_back(entry);
    }
    tracked_.push_back(entry);
    return result;
  }

  std::vector<TrajectoryEntry> trajectory(int32_t which) override {
    return which == BESLAM_TRAJECTORY_KEYFRAMES ? keyframes_ : tracked_;
  }

 private:
  long lookup(const beslam::sdk::Frame& frame) const {
    if (!file_.timestamped)
      return frame.index >= 0 && frame.index < static_cast<int64_t>(file_.poses.size()) ? static_cast<long>(frame.index)
                                                                                        : -1;
    const std::vector<double>& stamps = file_.poses.stamps;
    const auto it = std::lower_bound(stamps.begin(), stamps.end(), frame.timestamp);
    long best = -1;
    double best_diff = options_.max_time_diff;
    for (auto c : {it, it == stamps.begin() ? it : it - 1}) {
      if (c == stamps.end()) continue;
      const double diff = std::abs(*c - frame.timestamp);
      if (diff <= best_diff) best_diff = diff, best = static_cast<long>(c - stamps.begin());
    }
    return best;
  }

  Options options_;
  PoseFile file_;
  std::vector<TrajectoryEntry> tracked_, keyframes_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<PoseReplay>(kInfo))
