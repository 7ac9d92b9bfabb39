// A pipeline file: which dataset feeds which plugin in each of the five slots, and what the run writes.
//
//   dataset:  {type: kitti_odometry, root: ../data/kitti/odometry, sequence: "06"}
//   backend:  {plugin: backend_orb, features: 2000}
//   detector: {plugin: detector_oracle, position_noise: 0.3}      # optional slots may be left out
//   output:   {dir: out/run, masks: false}
//   pipeline: {prefetch: 3}                                       # scheduling (runner.hpp)
//
// loadPipeline() applies --set overrides, then validates everything the host knows at load time:
// unknown keys, wrong types, out-of-range values and unknown choices are beslam::Error messages naming
// the file, the line and the key ("kitti.yaml:7: dataset.frist: unknown key (known: ...)"). Plugin
// settings are validated against each plugin's own schema by resolvePlugins(). Any value may name
// the dataset's own settings as ${dataset.root}, ${dataset.sequence}, ... (after --set, before paths
// resolve), so one pipeline serves every sequence. Plugin, once the registry is
// loaded; relative paths resolve against the pipeline file's folder. The resolved YAML (every default
// filled in) is what a run writes as pipeline.resolved.yaml.
#pragma once

#include <yaml-cpp/yaml.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "beslam/common/frame_ranges.hpp"
#include "beslam/plugin.h"
#include "beslam/registry/registry.hpp"

namespace beslam::pipeline {

inline const char* const kSlots[] = {"detector", "motion_checker", "mask_generator", "reconstructor", "backend"};

// A resolved plugin configuration; owns the strings and lists its C view points into.
class PluginConfig {
 public:
  void add(const std::string& key, int32_t type, double number, const std::string& text,
           const std::vector<double>& list);
  const std::vector<beslam_config_value>& values() const;  // valid while this object lives unchanged

 private:
  struct Entry {
    std::string key;
    int32_t type;
    double number;
    std::string text;
    std::vector<double> list;
  };
  std::vector<std::unique_ptr<Entry>> entries_;
  mutable std::vector<beslam_config_value> view_;
};

struct SlotSpec {
  std::string slot;                          // "detector", ...
  std::string plugin_id;                     // empty: slot unused
  YAML::Node settings;                       // the slot's map without `plugin`
  const registry::Plugin* plugin = nullptr;  // set by resolvePlugins
  PluginConfig config;                       // set by resolvePlugins
};

// type synth: root is a cache folder, sequence a synth preset name or config file; the sequence is
// rendered there once (keyed by a hash of the full config) and then read as KITTI odometry.
struct DatasetSpec {
  std::string type, root, sequence, camera, ego_poses, synth_set;
  std::string calibration;  // a camera file (datasets/camera_file.hpp), "" for the layout's own camera
  int64_t first = 0, last = -1, step = 1;
  bool lidar = false, color = false;
  double camera_height = 0;              // metres over the road; 0: the dataset's own value (Dataset::cameraHeight)
  std::vector<FrameRange> black_frames;  // frames whose images load black (datasets::blackOut)
};

struct OutputSpec {
  std::string dir;
  bool masks = false;
  bool map_points = true;
  int samples = 6;                  // frames drawn to samples/ (0: none)
  bool octomap = false;             // static_map.bt
  double octomap_resolution = 0.2;  // metres
  double min_tracked_share = 0.5;   // fewer frames in the final trajectory fail the run (0: never)
};

struct EvaluationSpec {
  bool enabled = true;    // APE/RPE against the dataset's ground truth when it has one
  std::string alignment;  // none | se3 | sim3
  int64_t rpe_delta = 1;
};

// How the runner schedules the stages (prefetch never changes what they compute) and the motion
// checker's history when the world turns metric (runner.hpp).
struct RunSpec {
  int prefetch = 3;                 // frames prepared ahead on a producer thread (0: strictly one stage after another)
  int motion_replay_frames = 0;     // frames the motion checker is run on again with metric poses (0: none)
  bool motion_replay_boxes = true;  // replay the boxes at the final poses; false: the online poses alone
};

struct PipelineSpec {
  std::string path;      // the pipeline file
  std::string base_dir;  // its folder: relative paths resolve here
  DatasetSpec dataset;
  std::vector<std::string> plugin_paths;
  std::map<std::string, SlotSpec> slots;  // all five, possibly unused
  OutputSpec output;
  EvaluationSpec evaluation;
  RunSpec run;
  YAML::Node document;  // after overrides, host defaults filled in
};

// Reads, overrides and validates a pipeline file. Throws beslam::Error naming file, line and key.
PipelineSpec loadPipeline(const std::string& path, const std::vector<std::string>& overrides = {});

// Looks up each used slot's plugin (right kind) and validates its settings against its schema,
// filling defaults into spec.document. Throws beslam::Error naming file, line and key.
void resolvePlugins(PipelineSpec& spec, const registry::Registry& registry);

// Validates one YAML map against a schema and returns resolved values. `where` prefixes key names
// ("detector" -> "detector.min_score"); unknown keys are errors unless listed in `ignore`.
PluginConfig validateSettings(const YAML::Node& map, const std::vector<registry::ConfigField>& fields,
                              const std::string& where, const std::string& file, const std::string& base_dir,
                              const std::vector<std::string>& ignore = {});

}  // namespace beslam::pipeline
