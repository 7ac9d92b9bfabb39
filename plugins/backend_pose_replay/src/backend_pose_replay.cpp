// backend_pose_replay: a backend that replays camera poses from a file instead of estimating them.
// It lets the semantic plugins (detector, motion checker, masks, reconstructor) run on ground truth or
// on an external odometry, and is how the motion benchmark runs. KITTI files are matched to frames by
// row = frame index; TUM files by nearest timestamp within max_time_diff. A frame with no pose is
// reported LOST and left out of the trajectories, never invented. Every keyframe_interval-th tracked
// frame is declared a keyframe so a reconstructor downstream gets work.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "beslam/sdk/sdk.hpp"

namespace {

namespace field = beslam::sdk::field;
using beslam::sdk::TrajectoryEntry;

const beslam_config_field kFields[] = {
    field::Path("poses", nullptr, "pose file: KITTI (12 numbers a row) or TUM (t x y z qx qy qz qw)"),
    field::String("format", "auto", "auto|kitti|tum", "file format; auto decides by the column count"),
    field::Double("max_time_diff", "0.02", 0, 10, "TUM: largest |t_frame - t_pose| accepted (s)"),
    field::Int("keyframe_interval", "5", 1, 1000, "every n-th tracked frame becomes a keyframe"),
};

struct PoseFile {
  bool timestamped = false;
  std::vector<double> stamps;
  std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>> poses;
};

PoseFile readPoses(const std::string& path, const std::string& format) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open pose file");
  PoseFile file;
  std::string line;
  int line_no = 0;
  int columns = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream ss(line);
    std::vector<double> v;
    std::string token;
    while (ss >> token) {
      try {
        size_t used = 0;
        v.push_back(std::stod(token, &used));
        if (used != token.size()) throw std::invalid_argument(token);
      } catch (const std::exception&) {
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": '" + token + "' is not a number");
      }
      if (!std::isfinite(v.back()))
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": non-finite value '" + token + "'");
    }
    if (columns == 0) {
      columns = static_cast<int>(v.size());
      if (format == "kitti" && columns != 12)
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": KITTI rows have 12 numbers, this has " +
                                 std::to_string(columns));
      if (format == "tum" && columns != 8)
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": TUM rows have 8 numbers, this has " +
                                 std::to_string(columns));
      if (columns != 12 && columns != 8)
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected 12 (KITTI) or 8 (TUM) numbers, got " +
                                 std::to_string(columns));
      file.timestamped = columns == 8;
    } else if (static_cast<int>(v.size()) != columns) {
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected " + std::to_string(columns) +
                               " numbers, got " + std::to_string(v.size()));
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    if (columns == 12) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) T.matrix()(r, c) = v[r * 4 + c];
      const Eigen::Matrix3d R = T.linear();
      if ((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-3)
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": rotation is not orthonormal");
      file.stamps.push_back(static_cast<double>(file.poses.size()));
    } else {
      Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
      if (q.norm() < 1e-9) throw std::runtime_error(path + ":" + std::to_string(line_no) + ": zero quaternion");
      T.linear() = q.normalized().toRotationMatrix();
      T.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
      if (!file.stamps.empty() && v[0] <= file.stamps.back())
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": timestamps must increase");
      file.stamps.push_back(v[0]);
    }
    file.poses.push_back(T);
  }
  if (file.poses.empty()) throw std::runtime_error(path + ": pose file has no poses");
  return file;
}

class PoseReplay : public beslam::sdk::Backend {
 public:
  PoseReplay(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : file_(readPoses(config.getString("poses"), config.getString("format"))),
        max_time_diff_(config.getDouble("max_time_diff")),
        keyframe_interval_(config.getInt("keyframe_interval")) {
    context.info("replaying " + std::to_string(file_.poses.size()) + " poses from " + config.getString("poses"));
  }

  std::optional<Eigen::Isometry3d> predictPose(const beslam::sdk::Frame& frame) override {
    const long i = lookup(frame);
    if (i < 0) return std::nullopt;
    return file_.poses[i];
  }

  beslam::sdk::TrackResult track(const beslam::sdk::Frame& frame, const cv::Mat&,
                                 const std::vector<beslam_box3d>&) override {
    beslam::sdk::TrackResult result;
    const long i = lookup(frame);
    if (i < 0) {
      result.state = tracked_.empty() ? BESLAM_TRACKING_NOT_INITIALIZED : BESLAM_TRACKING_LOST;
      return result;
    }
    result.state = BESLAM_TRACKING_OK;
    result.T_world_cam = file_.poses[i];
    const TrajectoryEntry entry{frame.index, frame.timestamp, file_.poses[i]};
    if (static_cast<int64_t>(tracked_.size()) % keyframe_interval_ == 0) {
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
      return frame.index >= 0 && frame.index < static_cast<int64_t>(file_.poses.size()) ? static_cast<long>(frame.index) : -1;
    const auto it = std::lower_bound(file_.stamps.begin(), file_.stamps.end(), frame.timestamp);
    long best = -1;
    double best_diff = max_time_diff_;
    for (auto c : {it, it == file_.stamps.begin() ? it : it - 1}) {
      if (c == file_.stamps.end()) continue;
      const double diff = std::abs(*c - frame.timestamp);
      if (diff <= best_diff) best_diff = diff, best = static_cast<long>(c - file_.stamps.begin());
    }
    return best;
  }

  PoseFile file_;
  double max_time_diff_;
  int64_t keyframe_interval_;
  std::vector<TrajectoryEntry> tracked_, keyframes_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<PoseReplay>(
    {"backend_pose_replay", "Pose replay", "Replays camera poses from a KITTI or TUM file (ground truth or external odometry)",
     {1, 0, 0}, kFields}))
