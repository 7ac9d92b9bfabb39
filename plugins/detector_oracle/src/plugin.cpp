// detector_oracle: ground-truth tracking labels (KITTI label_02 or `beslam synth`) as a detector with
// configurable faults, for ablations (oracle.hpp, docs/detectors.md).
#include <filesystem>

#include "beslam/detector_oracle/oracle.hpp"
#include "beslam/detector_replay/replay.hpp"
#include "beslam/sdk/sdk.hpp"
#include "detector_oracle_settings.hpp"  // Options and kSettings, from settings.json

namespace {

namespace fs = std::filesystem;
using namespace beslam::detector_oracle;

const beslam::sdk::PluginInfo kInfo(
    "detector_oracle", "Label oracle",
    "Ground-truth tracking labels with configurable noise, misses and false positives (ablations)", {1, 0, 0},
    kSettings);

class DetectorOracle : public beslam::sdk::Detector {
 public:
  DetectorOracle(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : context_(context), options_(kSettings.read(config)), labels_(options_.labels), motion_(options_.motion) {
    if (!labels_.empty()) load();
  }

  std::vector<beslam_box3d> detect(const beslam::sdk::Frame& frame) override {
    if (!oracle_) {
      labels_ = labelsFromImage(frame.image_path);
      load();
    }
    if (frame.index < 0 || frame.index > oracle_->lastFrame()) {
      if (options_.missing_empty) return {};
      throw std::runtime_error(labels_ + ": frame " + std::to_string(frame.index) +
                               " is past the last labelled frame (" + std::to_string(oracle_->lastFrame()) +
                               "; set on_missing_frame: empty to allow)");
    }
    return oracle_->detect(frame.index);
  }

 private:
  void load() {
    if (fs::is_directory(labels_)) {
      if (options_.sequence.empty())
        throw beslam::sdk::ConfigError("sequence: required when labels is a folder (" + labels_ + ")");
      labels_ = (fs::path(labels_) / (options_.sequence + ".txt")).string();
    }
    if (options_.true_motion &&
        motion_.empty()) {  // beslam synth: sequences/NN/label_02/NN.txt beside sequences/NN/objects_motion.txt
      motion_ = (fs::path(labels_).parent_path().parent_path() / "objects_motion.txt").string();
      if (!fs::exists(motion_))
        throw beslam::sdk::ConfigError("true_motion: " + motion_ +
                                       " does not exist (only beslam synth sequences have it)");
    }
    oracle_.emplace(readTruth(labels_, motion_), options_.oracle);
    context_.info("label oracle over " + labels_ + " (" + std::to_string(oracle_->lastFrame() + 1) + " frames)");
  }

  // The label file beside a frame's image: KITTI tracking or the beslam synth layout.
  static std::string labelsFromImage(const std::string& image_path) {
    if (image_path.empty())
      throw std::runtime_error("detector_oracle: no `labels` set and the frame has no image path to find them from");
    const fs::path folder = fs::path(image_path).parent_path();  // .../image_02/0007 or .../NN/image_0
    const fs::path tracking = folder.parent_path().parent_path() / "label_02" / (folder.filename().string() + ".txt");
    if (fs::exists(tracking)) return tracking.string();
    const fs::path seq = folder.parent_path();
    const fs::path synth = seq / "label_02" / (seq.filename().string() + ".txt");
    if (fs::exists(synth)) return synth.string();
    throw std::runtime_error("detector_oracle: no `labels` set and neither " + tracking.string() + " nor " +
                             synth.string() + " exists (for image " + image_path + ")");
  }

  const beslam::sdk::Context& context_;
  const Options options_;
  std::string labels_, motion_;  // as set, then as found (labels from the image path, motion beside them)
  std::optional<LabelOracle> oracle_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<DetectorOracle>(kInfo))
