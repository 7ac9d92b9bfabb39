// label_replay: a replay-style detector built on the SDK alone - KITTI object labels (one
// <frame:06d>.txt per frame, "type truncated occluded alpha x1 y1 x2 y2 h w l x y z ry [score]") read with
// the SDK's formats component and returned as boxes. A missing file is a frame without objects, or an
// error with `missing: error`; a malformed row stops the run with "file:line: cause".
#include <cstdio>
#include <filesystem>

#include "beslam/formats/geometry.hpp"
#include "beslam/formats/labels.hpp"
#include "beslam/sdk/sdk.hpp"
#include "label_replay_settings.hpp"  // Options and kSettings, generated from label_replay.settings.json

namespace {

// What `beslam plugins` shows: id, name, one line, version, settings.
const beslam::sdk::PluginInfo kInfo("label_replay", "KITTI label replay (template)",
                                    "Replays KITTI object label files as detections", {1, 0, 0}, kSettings);

class LabelReplay : public beslam::sdk::Detector {
 public:
  LabelReplay(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : options_(kSettings.read(config)) {
    if (!std::filesystem::is_directory(options_.folder))
      throw beslam::sdk::ConfigError("folder: '" + options_.folder + "' is not a folder");
    context.info("replaying KITTI labels from " + options_.folder);
  }

  std::vector<beslam_box3d> detect(const beslam::sdk::Frame& frame) override {
    char name[32];
    std::snprintf(name, sizeof name, "%06lld.txt", static_cast<long long>(frame.index));
    const std::filesystem::path file = std::filesystem::path(options_.folder) / name;
    if (!std::filesystem::exists(file)) {
      if (options_.missing_is_error) throw std::runtime_error(file.string() + ": no label file for this frame");
      return {};
    }
    std::vector<beslam_box3d> boxes;
    for (const beslam::formats::ObjectLabel& label : beslam::formats::readObjectLabels(file.string())) {
      int32_t class_id = BESLAM_CLASS_UNKNOWN;
      if (label.isDontCare() || !beslam::formats::kittiClass(label.type, class_id)) continue;
      if (label.score && *label.score < options_.min_score) continue;
      beslam_box3d box = beslam::formats::boxFromKitti(class_id, label.h, label.w, label.l, label.p_cam_bottom.x(),
                                                       label.p_cam_bottom.y(), label.p_cam_bottom.z(), label.ry);
      box.score = label.score ? static_cast<float>(*label.score) : 1.0f;
      boxes.push_back(box);
    }
    return boxes;
  }

 private:
  Options options_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<LabelReplay>(kInfo))
