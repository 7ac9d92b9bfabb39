// detector_replay: published 3D detection results replayed as a detector (see replay.hpp, nuscenes.hpp and
// docs/detectors.md). Everything is parsed when the instance is created, so a malformed file stops the run
// before its first frame; detect() is a lookup.
#include <filesystem>
#include <sstream>

#include "beslam/detector_replay/nuscenes.hpp"
#include "beslam/detector_replay/replay.hpp"
#include "beslam/formats/trajectory.hpp"
#include "beslam/sdk/sdk.hpp"
#include "detector_replay_settings.hpp"  // Options and kSettings, from settings.json

namespace {

namespace fs = std::filesystem;
using namespace beslam::detector_replay;

const beslam::sdk::PluginInfo kInfo(
    "detector_replay", "Detection replay",
    "Replays published 3D detections: nuScenes results JSON (BEVFormer, Fast-BEV), KITTI labels, AB3DMOT rows",
    {1, 0, 0}, kSettings);

class DetectorReplay : public beslam::sdk::Detector {
 public:
  DetectorReplay(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : DetectorReplay(context, kSettings.read(config)) {}

  DetectorReplay(const beslam::sdk::Context& context, const Options& options)
      : context_(context),
        format_(options.format),
        path_(options.path),
        missing_empty_(options.missing_empty),
        filter_(options.filter),
        policy_(options.policy) {
    const Filter& filter = filter_;
    const std::string& st = options.score_transform;
    transform_ =
        st == "sigmoid" || (st == "auto" && format_ == "ab3dmot") ? ScoreTransform::sigmoid : ScoreTransform::none;
    const std::string& sequence = options.sequence;

    if (format_ == "ab3dmot") {
      if (fs::is_directory(path_)) {
        if (sequence.empty())
          throw beslam::sdk::ConfigError("sequence: required when path is a folder (" + path_ + ")");
        int found = 0;
        for (const char* cls : {"Car", "Pedestrian", "Cyclist"}) {
          int32_t id = 0;
          kittiClass(cls, id);
          if (!filter.classes.empty() &&
              std::find(filter.classes.begin(), filter.classes.end(), id) == filter.classes.end())
            continue;
          const fs::path file = fs::path(path_) / cls / (sequence + ".txt");
          if (!fs::exists(file)) continue;
          readAb3dmotFile(file.string(), filter, policy_, transform_, table_, report_);
          sources_ += (found++ ? ", " : "") + file.string();
        }
        if (found == 0)
          throw std::runtime_error(path_ + ": no detection file <Class>/" + sequence + ".txt for the selected classes");
      } else {
        readAb3dmotFile(path_, filter, policy_, transform_, table_, report_);
        sources_ = path_;
      }
    } else if (format_ == "kitti_tracking") {
      std::string file = path_;
      if (fs::is_directory(path_)) {
        if (sequence.empty())
          throw beslam::sdk::ConfigError("sequence: required when path is a folder (" + path_ + ")");
        file = (fs::path(path_) / (sequence + ".txt")).string();
      }
      readKittiTrackingFile(file, filter, policy_, transform_, table_, report_);
      sources_ = file;
    } else if (format_ == "kitti_object") {
      if (!fs::is_directory(path_)) throw std::runtime_error(path_ + ": kitti_object needs a label_2 folder");
      sources_ = path_;
    } else {  // nuscenes
      NuScenesOptions o;
      o.results = path_;
      const std::string& tokens = options.sample_tokens;
      if (tokens.empty()) throw beslam::sdk::ConfigError("sample_tokens: required for format nuscenes");
      o.frames = readNuScenesFrames(tokens);
      const std::string& poses = options.ego_poses;
      if (!poses.empty()) {
        const beslam::formats::Trajectory t = beslam::formats::readKitti(poses);
        o.ego_poses.assign(t.poses.begin(), t.poses.end());
      }
      try {
        o.T_ego_cam = poseFromTranslationQuaternion(options.camera_extrinsic, "camera_extrinsic");
      } catch (const std::invalid_argument& e) {
        throw beslam::sdk::ConfigError(e.what());
      }
      o.filter = filter;
      o.policy = policy_;
      readNuScenes(o, table_, covered_, report_);
      frame_count_ = static_cast<int64_t>(o.frames.tokens.size());
      sources_ = path_ + " (tokens " + tokens + ")";
    }
    std::ostringstream msg;
    msg << "replaying " << report_.boxes << " boxes (" << report_.rows << " rows, " << report_.filtered
        << " filtered) from " << sources_;
    context.info(msg.str());
    if (report_.skipped > 0) {
      std::ostringstream warn;
      warn << "skipped " << report_.skipped << " malformed rows; first: " << report_.problems.front();
      context.warn(warn.str());
    }
  }

  std::vector<beslam_box3d> detect(const beslam::sdk::Frame& frame) override {
    if (format_ == "kitti_object") return detectObjectFolder(frame.index);
    bool missing = false;
    std::string why;
    if (format_ == "nuscenes") {
      if (frame.index < 0 || frame.index >= frame_count_) {
        missing = true;
        why = "no sample token for this frame (the token list has " + std::to_string(frame_count_) + ")";
      } else if (!covered_[static_cast<size_t>(frame.index)]) {
        missing = true;
        why = "no results (or no ego pose) for its sample token";
      }
    } else if (frame.index < 0 || frame.index > table_.lastFrame()) {
      missing = true;
      why = "past the last frame (" + std::to_string(table_.lastFrame()) + ") of the detections";
    }
    if (missing) return missingFrame(frame.index, why);
    return table_.at(frame.index);
  }

  ~DetectorReplay() override {
    if (missing_frames_ > 0)
      context_.warn(std::to_string(missing_frames_) + " frames had no detections in " + sources_ +
                    " (replayed as empty)");
  }

 private:
  std::vector<beslam_box3d> missingFrame(int64_t index, const std::string& why) {
    if (!missing_empty_)
      throw std::runtime_error(sources_ + ": frame " + std::to_string(index) + ": " + why +
                               " (set on_missing_frame: empty to replay such frames without boxes)");
    ++missing_frames_;
    return {};
  }

  std::vector<beslam_box3d> detectObjectFolder(int64_t index) {
    char name[32];
    std::snprintf(name, sizeof name, "%06lld.txt", static_cast<long long>(index));
    const fs::path file = fs::path(path_) / name;
    if (!fs::exists(file)) return missingFrame(index, "no label file " + file.string());
    DetectionTable table;
    Report report;
    readKittiObjectFile(file.string(), index, filter_, policy_, transform_, table, report);
    if (report.skipped > 0)
      context_.warn("skipped " + std::to_string(report.skipped) + " malformed rows; first: " + report.problems.front());
    return table.at(index);
  }

  const beslam::sdk::Context& context_;
  std::string format_, path_, sources_;
  bool missing_empty_;
  Filter filter_;
  Policy policy_ = Policy::stop;
  ScoreTransform transform_ = ScoreTransform::none;
  DetectionTable table_;
  Report report_;
  std::vector<char> covered_;
  int64_t frame_count_ = 0;
  int64_t missing_frames_ = 0;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<DetectorReplay>(kInfo))
