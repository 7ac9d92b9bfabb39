#include "beslam/pipeline/spec.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/common/yaml_load.hpp"
#include "beslam/common/yaml_set.hpp"
#include "dataset_fields.hpp"     // kDatasetFields, from sections/dataset.json
#include "evaluation_fields.hpp"  // kEvaluationFields, from sections/evaluation.json
#include "output_fields.hpp"      // kOutputFields, from sections/output.json
#include "pipeline_fields.hpp"    // kPipelineFields, from sections/pipeline.json

namespace fs = std::filesystem;

namespace beslam::pipeline {

void PluginConfig::add(const std::string& key, int32_t type, double number, const std::string& text,
                       const std::vector<double>& list) {
  entries_.push_back(std::make_unique<Entry>(Entry{key, type, number, text, list}));
  view_.clear();
}

const std::vector<beslam_config_value>& PluginConfig::values() const {
  if (view_.size() != entries_.size()) {
    view_.clear();
    for (const auto& e : entries_) {
      beslam_config_value v{};
      v.key = e->key.c_str();
      v.type = e->type;
      v.number = e->number;
      v.text = e->text.c_str();
      v.list = e->list.empty() ? nullptr : e->list.data();
      v.list_size = e->list.size();
      view_.push_back(v);
    }
  }
  return view_;
}

namespace {

using registry::ConfigField;

// "file:line" for a node read from the file, "file (--set)" for one an override created.
std::string at(const std::string& file, const YAML::Node& node) { return yamlWhere(file, node, " (--set)"); }

[[noreturn]] void fail(const std::string& file, const YAML::Node& node, const std::string& key,
                       const std::string& message) {
  throw Error(at(file, node) + ": " + key + ": " + message);
}

std::string rangeText(const ConfigField& f) {
  std::ostringstream ss;
  ss << "[" << f.min_value << ", " << f.max_value << "]";
  return ss.str();
}

double parseNumber(const YAML::Node& node, const ConfigField& f, const std::string& file, const std::string& key,
                   bool integer) {
  if (!node.IsScalar()) fail(file, node, key, std::string("expected ") + (integer ? "an integer" : "a number"));
  const std::string text = node.Scalar();
  double value = 0;
  try {
    if (integer) {
      size_t used = 0;
      const long long v = std::stoll(text, &used);
      if (used != text.size()) throw std::invalid_argument(text);
      value = static_cast<double>(v);
    } else {
      value = node.as<double>();
    }
  } catch (const std::exception&) {
    fail(file, node, key, std::string("expected ") + (integer ? "an integer" : "a number") + ", got '" + text + "'");
  }
  if (!std::isfinite(value)) fail(file, node, key, "value must be finite, got '" + text + "'");
  if (f.min_value <= f.max_value && (value < f.min_value || value > f.max_value))
    fail(file, node, key, "value " + text + " is out of range " + rangeText(f));
  return value;
}

std::string knownKeys(const std::vector<ConfigField>& fields, const std::vector<std::string>& extra) {
  std::string known;
  for (const auto& k : extra) known += (known.empty() ? "" : ", ") + k;
  for (const auto& f : fields) known += (known.empty() ? "" : ", ") + f.key;
  return known.empty() ? "none" : known;
}

// Relative paths resolve against the pipeline file's folder. A path the file system cannot even look at
// (a name longer than the system allows, ...) is one error naming it (found by the pipeline_yaml fuzzer:
// std::filesystem's exception escaped).
std::string resolvePath(const std::string& text, const std::string& base_dir, const std::string& file,
                        const YAML::Node& node, const std::string& key) {
  if (text.empty() || fs::path(text).is_absolute() || base_dir.empty()) return text;
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(fs::path(base_dir) / text, ec);
  if (ec)
    fail(file, node, key, "path '" + (text.size() > 80 ? text.substr(0, 80) + "..." : text) + "': " + ec.message());
  return resolved.string();
}

// The pipeline file's own sections, declared as data in platform/pipeline/sections/*.json.
template <size_t N>
std::vector<ConfigField> fieldsOf(const beslam_config_field (&raw)[N]) {
  std::vector<ConfigField> fields;
  for (const beslam_config_field& f : raw) fields.push_back(registry::fieldOf(f));
  return fields;
}
std::vector<ConfigField> datasetFields() { return fieldsOf(kDatasetFields); }
std::vector<ConfigField> outputFields() { return fieldsOf(kOutputFields); }
std::vector<ConfigField> runFields() { return fieldsOf(kPipelineFields); }
std::vector<ConfigField> evaluationFields() { return fieldsOf(kEvaluationFields); }

const beslam_config_value& value(const PluginConfig& c, const std::string& key) {
  for (const auto& v : c.values())
    if (key == v.key) return v;
  throw std::logic_error("no value " + key);
}

// Replaces ${dataset.KEY} in every scalar of node with the dataset's own (pre-resolution) value, so
// plugin settings follow --set dataset.root / dataset.sequence. An unknown placeholder is an error.
void substitutePlaceholders(YAML::Node node, const YAML::Node& dataset, const std::string& file,
                            const std::string& where) {
  if (node.IsMap()) {
    for (auto kv : node) {
      if (!kv.first.IsScalar()) throwAt(file, "keys must be plain names", kv.first.Mark().line + 1);
      const std::string key = kv.first.as<std::string>();
      if (where == "dataset" && (key == "root" || key == "sequence")) continue;
      substitutePlaceholders(kv.second, dataset, file, where.empty() ? key : where + "." + key);
    }
    return;
  }
  if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) substitutePlaceholders(node[i], dataset, file, where);
    return;
  }
  if (!node.IsScalar()) return;
  std::string text = node.Scalar();
  if (text.find("${") == std::string::npos) return;
  std::string out;
  std::size_t pos = 0;
  while (true) {
    const std::size_t open = text.find("${", pos);
    if (open == std::string::npos) break;
    const std::size_t close = text.find('}', open);
    if (close == std::string::npos) fail(file, node, where, "unterminated placeholder in '" + text + "'");
    const std::string name = text.substr(open + 2, close - open - 2);
    const std::string prefix = "dataset.";
    const bool in_dataset = name.rfind(prefix, 0) == 0 && dataset.IsMap();
    const YAML::Node value = in_dataset ? dataset[name.substr(prefix.size())] : YAML::Node();
    if (!value.IsDefined() || !value.IsScalar())
      fail(file, node, where,
           "unknown placeholder ${" + name +
               "} (known: ${dataset.root}, ${dataset.sequence}, "
               "any other scalar of dataset)");
    out += text.substr(pos, open - pos) + value.Scalar();
    pos = close + 1;
  }
  out += text.substr(pos);
  node = out;
}

}  // namespace

PluginConfig validateSettings(const YAML::Node& map_in, const std::vector<ConfigField>& fields,
                              const std::string& where, const std::string& file, const std::string& base_dir,
                              const std::vector<std::string>& ignore) {
  YAML::Node map = map_in;
  if (!map.IsMap()) fail(file, map, where, "expected a map of settings");
  for (const auto& kv : map) {
    if (!kv.first.IsScalar()) throwAt(file, where + ": keys must be plain names", kv.first.Mark().line + 1);
    const std::string key = kv.first.as<std::string>();
    bool known = std::find(ignore.begin(), ignore.end(), key) != ignore.end();
    for (const auto& f : fields) known = known || f.key == key;
    if (!known) fail(file, kv.first, where + "." + key, "unknown key (known: " + knownKeys(fields, ignore) + ")");
  }
  PluginConfig config;
  for (const ConfigField& f : fields) {
    const std::string key = where + "." + f.key;
    YAML::Node node = map[f.key];
    if (!node.IsDefined() || node.IsNull()) {
      if (f.required) fail(file, map, key, "required setting is missing");
      try {
        node = YAML::Load(f.default_value);
      } catch (const YAML::Exception& e) {
        throw Error("plugin schema: default of " + key + " is not YAML: " + e.msg);
      }
      map[f.key] = node;
    }
    switch (f.type) {
      case BESLAM_CONFIG_BOOL: {
        bool b = false;
        if (!node.IsScalar() || !YAML::convert<bool>::decode(node, b))
          fail(file, node, key, "expected true or false, got '" + yamlText(node) + "'");
        config.add(f.key, f.type, b ? 1.0 : 0.0, "", {});
        break;
      }
      case BESLAM_CONFIG_INT:
      case BESLAM_CONFIG_DOUBLE:
        config.add(f.key, f.type, parseNumber(node, f, file, key, f.type == BESLAM_CONFIG_INT), "", {});
        break;
      case BESLAM_CONFIG_STRING:
      case BESLAM_CONFIG_PATH: {
        if (!node.IsScalar()) fail(file, node, key, "expected a string");
        std::string text = node.Scalar();
        if (!f.choices.empty()) {
          bool ok = false;
          std::stringstream ss(f.choices);
          for (std::string c; std::getline(ss, c, '|');) ok = ok || c == text;
          if (!ok) fail(file, node, key, "'" + text + "' is not one of " + f.choices);
        }
        if (f.type == BESLAM_CONFIG_PATH) {
          text = resolvePath(text, base_dir, file, node, key);
          if (!text.empty()) map[f.key] = text;
        }
        config.add(f.key, f.type, 0, text, {});
        break;
      }
      case BESLAM_CONFIG_DOUBLE_LIST: {
        if (!node.IsSequence()) fail(file, node, key, "expected a list of numbers, e.g. [1.0, 2.0]");
        std::vector<double> list;
        for (const auto& item : node) list.push_back(parseNumber(item, f, file, key, false));
        config.add(f.key, f.type, 0, "", list);
        break;
      }
      default:
        throw Error(key + ": unknown configuration type " + std::to_string(f.type));
    }
  }
  return config;
}

// loadPipeline without its last guard (below).
static PipelineSpec loadPipelineUnguarded(const std::string& path, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throwAt(path, "no such pipeline file");
  if (fs::is_directory(path, ec)) throwAt(path, "is a folder, not a pipeline file");
  PipelineSpec spec;
  spec.path = path;
  spec.base_dir = fs::absolute(path).parent_path().string();
  spec.document = loadYamlFile(path);  // duplicate keys, alias bombs and deep nesting are errors
  YAML::Node& doc = spec.document;
  if (doc.IsNull() || !doc.IsDefined()) throwAt(path, "the pipeline file is empty");
  if (!doc.IsMap()) throwAt(path, "a pipeline must be a map with dataset, backend, ... sections", doc.Mark().line + 1);
  for (const std::string& o : overrides) {
    try {
      applySetOverride(doc, o);
    } catch (const Error& e) {
      throwAt(path, e.what());
    }
  }

  substitutePlaceholders(doc, doc["dataset"], path, "");

  static const std::vector<std::string> top = {"name",           "description",   "dataset",  "plugin_paths",
                                               "output",         "evaluation",    "detector", "motion_checker",
                                               "mask_generator", "reconstructor", "backend",  "pipeline"};
  for (const auto& kv : doc) {
    const std::string key = kv.first.as<std::string>();
    if (std::find(top.begin(), top.end(), key) == top.end()) {
      std::string known;
      for (const auto& t : top) known += (known.empty() ? "" : ", ") + t;
      fail(path, kv.first, key, "unknown key (known: " + known + ")");
    }
  }

  if (!doc["dataset"].IsDefined()) throwAt(path, "dataset: required section is missing");
  const PluginConfig dataset = validateSettings(doc["dataset"], datasetFields(), "dataset", path, spec.base_dir);
  spec.dataset.type = value(dataset, "type").text;
  spec.dataset.root = value(dataset, "root").text;
  spec.dataset.sequence = value(dataset, "sequence").text;
  spec.dataset.camera = value(dataset, "camera").text;
  spec.dataset.first = static_cast<int64_t>(value(dataset, "first").number);
  spec.dataset.last = static_cast<int64_t>(value(dataset, "last").number);
  spec.dataset.step = static_cast<int64_t>(value(dataset, "step").number);
  spec.dataset.lidar = value(dataset, "lidar").number != 0;
  spec.dataset.color = value(dataset, "color").number != 0;
  spec.dataset.ego_poses = value(dataset, "ego_poses").text;
  spec.dataset.calibration = value(dataset, "calibration").text;
  spec.dataset.camera_height = value(dataset, "camera_height").number;
  spec.dataset.synth_set = value(dataset, "synth_set").text;
  if (const std::string black = value(dataset, "black_frames").text; !black.empty()) {
    try {
      spec.dataset.black_frames = parseFrameRanges(black);
    } catch (const Error& e) {
      fail(path, doc["dataset"]["black_frames"], "dataset.black_frames", e.what());
    }
  }
  if (spec.dataset.last >= 0 && spec.dataset.last < spec.dataset.first)
    fail(path, doc["dataset"]["last"], "dataset.last", "is before dataset.first");

  if (!doc["output"].IsDefined() || doc["output"].IsNull()) doc["output"] = YAML::Node(YAML::NodeType::Map);
  const PluginConfig output = validateSettings(doc["output"], outputFields(), "output", path, "");
  spec.output.dir = value(output, "dir").text;
  spec.output.masks = value(output, "masks").number != 0;
  spec.output.map_points = value(output, "map_points").number != 0;
  spec.output.samples = static_cast<int>(value(output, "samples").number);
  spec.output.octomap = value(output, "octomap").number != 0;
  spec.output.octomap_resolution = value(output, "octomap_resolution").number;
  spec.output.min_tracked_share = value(output, "min_tracked_share").number;

  if (!doc["evaluation"].IsDefined() || doc["evaluation"].IsNull()) doc["evaluation"] = YAML::Node(YAML::NodeType::Map);
  const PluginConfig evaluation = validateSettings(doc["evaluation"], evaluationFields(), "evaluation", path, "");
  spec.evaluation.enabled = value(evaluation, "enabled").number != 0;
  spec.evaluation.alignment = value(evaluation, "alignment").text;
  spec.evaluation.rpe_delta = static_cast<int64_t>(value(evaluation, "rpe_delta").number);

  if (!doc["pipeline"].IsDefined() || doc["pipeline"].IsNull()) doc["pipeline"] = YAML::Node(YAML::NodeType::Map);
  const PluginConfig run = validateSettings(doc["pipeline"], runFields(), "pipeline", path, "");
  spec.run.prefetch = static_cast<int>(value(run, "prefetch").number);
  spec.run.motion_replay_frames = static_cast<int>(value(run, "motion_replay_frames").number);
  spec.run.motion_replay_boxes = std::string(value(run, "motion_replay").text) == "boxes";

  if (YAML::Node paths = doc["plugin_paths"]; paths.IsDefined() && !paths.IsNull()) {
    if (!paths.IsSequence()) fail(path, paths, "plugin_paths", "expected a list of folders");
    for (const auto& p : paths) {
      if (!p.IsScalar()) fail(path, p, "plugin_paths", "expected a folder name");
      spec.plugin_paths.push_back(resolvePath(p.Scalar(), spec.base_dir, path, p, "plugin_paths"));
    }
  }

  for (const char* slot : kSlots) {
    SlotSpec s;
    s.slot = slot;
    YAML::Node node = doc[slot];
    if (node.IsDefined() && !node.IsNull()) {
      if (node.IsScalar()) fail(path, node, slot, "expected a map with a 'plugin' key (e.g. plugin: backend_orb)");
      if (!node.IsMap()) fail(path, node, slot, "expected a map with a 'plugin' key");
      YAML::Node id = node["plugin"];
      if (!id.IsDefined() || !id.IsScalar()) fail(path, node, std::string(slot) + ".plugin", "missing plugin id");
      s.plugin_id = id.Scalar() == "none" ? "" : id.Scalar();
      // Checked before the id is ever part of a file name: the registry opens <folder>/<id>.so.
      if (!s.plugin_id.empty() && !registry::isPluginId(s.plugin_id))
        fail(path, id, std::string(slot) + ".plugin",
             "'" + (s.plugin_id.size() > 80 ? s.plugin_id.substr(0, 80) + "..." : s.plugin_id) +
                 "' is not a plugin id (accepted: [a-z0-9_]+, the name of a library <id>.so in the plugin search "
                 "path, e.g. backend_orb, or none)");
      s.settings = node;
    }
    spec.slots[slot] = std::move(s);
  }
  if (spec.slots["backend"].plugin_id.empty())
    throwAt(path, "backend: a pipeline needs a backend (e.g. backend: {plugin: backend_orb})");
  return spec;
}

PipelineSpec loadPipeline(const std::string& path, const std::vector<std::string>& overrides) {
  // Every YAML shape the checks above did not foresee (a map as a key, a sequence where a name was
  // expected, ...) is still one error naming the file and line, never a yaml-cpp exception (found by
  // the pipeline_yaml fuzzer).
  try {
    return loadPipelineUnguarded(path, overrides);
  } catch (const YAML::Exception& e) {
    throwAt(path, "unexpected YAML structure: " + e.msg, e.mark.is_null() ? 0 : e.mark.line + 1);
  }
}

void resolvePlugins(PipelineSpec& spec, const registry::Registry& registry) {
  for (auto& [name, slot] : spec.slots) {
    if (slot.plugin_id.empty()) continue;
    const int32_t kind = registry::kindFromName(name);
    try {
      slot.plugin = &registry.find(slot.plugin_id, kind);
    } catch (const Error& e) {
      throw Error(at(spec.path, slot.settings["plugin"]) + ": " + name + ".plugin: " + e.what());
    }
    slot.config = validateSettings(slot.settings, slot.plugin->fields, name, spec.path, spec.base_dir, {"plugin"});
  }
}

}  // namespace beslam::pipeline
