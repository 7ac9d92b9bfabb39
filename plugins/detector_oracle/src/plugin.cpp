// detector_oracle: ground-truth tracking labels (KITTI label_02 or `beslam synth`) as a detector with
// configurable faults, for ablations (oracle.hpp, docs/detectors.md).
#include <filesystem>

#include "beslam/detector_oracle/oracle.hpp"
#include "beslam/detector_replay/replay.hpp"
#include "beslam/sdk/sdk.hpp"

namespace {

using beslam::sdk::nested;
using beslam::sdk::path;
using beslam::sdk::setting;
namespace fs = std::filesystem;
using namespace beslam::detector_oracle;

// What the plugin reads: the oracle's own options and where its labels come from.
struct Options {
  std::string labels, sequence, motion;
  bool true_motion = false;
  OracleOptions oracle;
  bool missing_empty = false;
};

// Each setting once: its schema entry and the member it sets.
// clang-format off: one setting a line
const beslam::sdk::Settings<Options> kSettings{
    path(&Options::labels, "labels", "\"\"",
         "tracking label file (label_02/0007.txt), or its folder with `sequence`; empty: found from the first frame's "
         "image path (KITTI tracking ROOT/image_02/SSSS/ -> ROOT/label_02/SSSS.txt, beslam synth sequences/NN/image_0/ "
         "-> sequences/NN/label_02/NN.txt)"),
    setting(&Options::sequence, "sequence", "\"\"", nullptr, "sequence name when labels is a folder (0007, 00)"),
    path(&Options::motion, "motion", "\"\"",
         "objects_motion.txt (beslam synth): pass the true motion state of each box"),
    setting(&Options::true_motion, "true_motion", "false",
            "pass the true motion states from the objects_motion.txt beside the labels (beslam synth sequences; "
            "`motion` unset)"),
    nested(&Options::oracle,
           beslam::sdk::parsed(&OracleOptions::classes, "classes", "all", nullptr,
                               "classes to keep: all, or a comma list of Car,Van,Truck,Pedestrian,Cyclist,Unknown",
                               beslam::detector_replay::parseClassList)),
    nested(&Options::oracle, setting(&OracleOptions::position_noise, "position_noise", "0.0", 0, 100,
                                     "m: std dev of each centre coordinate")),
    nested(&Options::oracle, setting(&OracleOptions::depth_noise_per_m, "depth_noise_per_m", "0.0", 0, 10,
                                     "std dev along the viewing ray per metre of range (monocular-like)")),
    nested(&Options::oracle, setting(&OracleOptions::size_noise, "size_noise", "0.0", 0, 10,
                                     "relative std dev of length, width, height")),
    nested(&Options::oracle, setting(&OracleOptions::yaw_noise, "yaw_noise", "0.0", 0, 10, "rad: std dev of the yaw")),
    nested(&Options::oracle,
           setting(&OracleOptions::miss_rate, "miss_rate", "0.0", 0, 1, "probability a true box is missed")),
    nested(&Options::oracle, setting(&OracleOptions::false_positives, "false_positives", "0.0", 0, 50,
                                     "mean false boxes per frame (Poisson)")),
    nested(&Options::oracle, setting(&OracleOptions::max_range, "max_range", "80", 5.01, 1000,
                                     "m: labels farther away are not detected")),
    nested(&Options::oracle, setting(&OracleOptions::seed, "seed", "0", 0, 4294967295.0,
                                     "random seed (a frame's boxes depend on seed and frame only)")),
    nested(&Options::oracle, setting(&OracleOptions::pass_track_ids, "pass_track_ids", "false",
                                     "keep the labels' track ids (default -1: the motion checker must track)")),
    beslam::sdk::choice(&Options::missing_empty, "on_missing_frame", "error", {{"error", false}, {"empty", true}},
                        "a frame past the last labelled frame"),
};
// clang-format on

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
