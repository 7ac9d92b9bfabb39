// detector_oracle: ground-truth tracking labels (KITTI label_02 or `beslam synth`) as a detector with
// configurable faults, for ablations (oracle.hpp, docs/detectors.md).
#include <filesystem>

#include "beslam/detector_oracle/oracle.hpp"
#include "beslam/detector_replay/replay.hpp"
#include "beslam/sdk/sdk.hpp"

namespace {

namespace field = beslam::sdk::field;
namespace fs = std::filesystem;
using namespace beslam::detector_oracle;

const beslam_config_field kFields[] = {
    field::Path("labels", "\"\"",
                "tracking label file (label_02/0007.txt), or its folder with `sequence`; empty: found from the first "
                "frame's image path (KITTI tracking ROOT/image_02/SSSS/ -> ROOT/label_02/SSSS.txt, beslam synth "
                "sequences/NN/image_0/ -> sequences/NN/label_02/NN.txt)"),
    field::String("sequence", "\"\"", nullptr, "sequence name when labels is a folder (0007, 00)"),
    field::Path("motion", "\"\"", "objects_motion.txt (beslam synth): pass the true motion state of each box"),
    field::Bool("true_motion", "false", "pass the true motion states from the objects_motion.txt beside the labels (beslam synth sequences; `motion` unset)"),
    field::String("classes", "all", nullptr, "classes to keep: all, or a comma list of Car,Van,Truck,Pedestrian,Cyclist,Unknown"),
    field::Double("position_noise", "0.0", 0, 100, "m: std dev of each centre coordinate"),
    field::Double("depth_noise_per_m", "0.0", 0, 10, "std dev along the viewing ray per metre of range (monocular-like)"),
    field::Double("size_noise", "0.0", 0, 10, "relative std dev of length, width, height"),
    field::Double("yaw_noise", "0.0", 0, 10, "rad: std dev of the yaw"),
    field::Double("miss_rate", "0.0", 0, 1, "probability a true box is missed"),
    field::Double("false_positives", "0.0", 0, 50, "mean false boxes per frame (Poisson)"),
    field::Double("max_range", "80", 5.01, 1000, "m: labels farther away are not detected"),
    field::Int("seed", "0", 0, 4294967295.0, "random seed (a frame's boxes depend on seed and frame only)"),
    field::Bool("pass_track_ids", "false", "keep the labels' track ids (default -1: the motion checker must track)"),
    field::String("on_missing_frame", "error", "error|empty", "a frame past the last labelled frame"),
};

class DetectorOracle : public beslam::sdk::Detector {
 public:
  DetectorOracle(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : context_(context),
        options_(options(config)),
        sequence_(config.getString("sequence")),
        motion_(config.getString("motion")),
        true_motion_(config.getBool("true_motion")),
        missing_empty_(config.getString("on_missing_frame") == "empty") {
    labels_ = config.getString("labels");
    if (!labels_.empty()) load();
  }

  std::vector<beslam_box3d> detect(const beslam::sdk::Frame& frame) override {
    if (!oracle_) {
      labels_ = labelsFromImage(frame.image_path);
      load();
    }
    if (frame.index < 0 || frame.index > oracle_->lastFrame()) {
      if (missing_empty_) return {};
      throw std::runtime_error(labels_ + ": frame " + std::to_string(frame.index) + " is past the last labelled frame (" +
                               std::to_string(oracle_->lastFrame()) + "; set on_missing_frame: empty to allow)");
    }
    return oracle_->detect(frame.index);
  }

 private:
  void load() {
    if (fs::is_directory(labels_)) {
      if (sequence_.empty()) throw beslam::sdk::ConfigError("sequence: required when labels is a folder (" + labels_ + ")");
      labels_ = (fs::path(labels_) / (sequence_ + ".txt")).string();
    }
    if (true_motion_ && motion_.empty()) {  // beslam synth: sequences/NN/label_02/NN.txt beside sequences/NN/objects_motion.txt
      motion_ = (fs::path(labels_).parent_path().parent_path() / "objects_motion.txt").string();
      if (!fs::exists(motion_))
        throw beslam::sdk::ConfigError("true_motion: " + motion_ + " does not exist (only beslam synth sequences have it)");
    }
    oracle_.emplace(readTruth(labels_, motion_), options_);
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
    throw std::runtime_error("detector_oracle: no `labels` set and neither " + tracking.string() + " nor " + synth.string() +
                             " exists (for image " + image_path + ")");
  }

  static OracleOptions options(const beslam::sdk::Config& config) {
    OracleOptions o;
    try {
      o.classes = beslam::detector_replay::parseClassList(config.getString("classes"));
    } catch (const std::invalid_argument& e) {
      throw beslam::sdk::ConfigError(std::string("classes: ") + e.what());
    }
    o.position_noise = config.getDouble("position_noise");
    o.depth_noise_per_m = config.getDouble("depth_noise_per_m");
    o.size_noise = config.getDouble("size_noise");
    o.yaw_noise = config.getDouble("yaw_noise");
    o.miss_rate = config.getDouble("miss_rate");
    o.false_positives = config.getDouble("false_positives");
    o.max_range = config.getDouble("max_range");
    o.seed = static_cast<uint64_t>(config.getInt("seed"));
    o.pass_track_ids = config.getBool("pass_track_ids");
    return o;
  }

  const beslam::sdk::Context& context_;
  OracleOptions options_;
  std::string labels_, sequence_, motion_;
  bool true_motion_;
  bool missing_empty_;
  std::optional<LabelOracle> oracle_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<DetectorOracle>(
    {"detector_oracle", "Label oracle",
     "Ground-truth tracking labels with configurable noise, misses and false positives (ablations)", {1, 0, 0}, kFields}))
