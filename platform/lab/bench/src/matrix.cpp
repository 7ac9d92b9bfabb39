// The matrix file: parse, validate, enumerate cells.
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "beslam/bench/bench.hpp"
#include "beslam/common/error.hpp"
#include "beslam/common/yaml_load.hpp"
#include "beslam/pipeline/spec.hpp"
#include "beslam/registry/registry.hpp"

namespace fs = std::filesystem;

namespace beslam::bench {
namespace {

int lineOf(const YAML::Node& node) { return node.Mark().line >= 0 ? node.Mark().line + 1 : 0; }

struct Reader {
  std::string path;
  fs::path base;

  [[noreturn]] void fail(const YAML::Node& node, const std::string& message) const {
    throwAt(path, message, lineOf(node));
  }

  void onlyKeys(const YAML::Node& map, const std::set<std::string>& allowed, const std::string& where) const {
    for (const auto& kv : map) {
      const std::string key = kv.first.as<std::string>();
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(kv.first, where + ": unknown key '" + key + "' (expected " + list + ")");
      }
    }
  }

  std::string scalar(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(node, what + ": expected a single value");
    return node.Scalar();
  }

  // A name that becomes one folder name (and part of a job script): letters, digits, _ . - and not
  // . or .. (so never a path of its own, nothing a shell would read).
  std::string folderSafe(const YAML::Node& n, const std::string& what) const {
    const std::string s = scalar(n, what);
    static const std::regex ok("[A-Za-z0-9_.-]+");
    if (!std::regex_match(s, ok) || s == "." || s == "..") {
      std::string shown;
      for (char c : s.substr(0, 80)) shown += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
      fail(n, what + ": '" + shown + (s.size() > 80 ? "..." : "") +
                  "' is not a folder-safe name (letters, digits, _ . -; not . or ..)");
    }
    return s;
  }

  std::string label(const YAML::Node& entry, const std::string& where) const {
    const YAML::Node n = entry["label"];
    if (!n.IsDefined()) fail(entry, where + ": 'label' is missing");
    return folderSafe(n, where + ".label");
  }

  // `set:` is a list of "key=value" strings or a map {key: value}.
  std::vector<std::string> sets(const YAML::Node& entry, const std::string& where) const {
    std::vector<std::string> out;
    const YAML::Node n = entry["set"];
    if (!n.IsDefined() || n.IsNull()) return out;
    if (n.IsSequence()) {
      for (const auto& item : n) {
        const std::string s = scalar(item, where + ".set");
        if (s.find('=') == std::string::npos || s.front() == '=')
          fail(item, where + ".set: '" + s + "' is not key=value");
        out.push_back(s);
      }
    } else if (n.IsMap()) {
      for (const auto& kv : n) {
        YAML::Emitter e;
        e << YAML::Flow << kv.second;
        out.push_back(kv.first.as<std::string>() + "=" + std::string(e.c_str()));
      }
    } else {
      fail(n, where + ".set: expected a list of key=value or a map");
    }
    return out;
  }

  // doc[key]: a non-empty list of maps, each with a label unique in the list and only `allowed` keys;
  // `each(entry, "key[i]", label)` reads the rest of an entry.
  template <class Each>
  void labelledList(const YAML::Node& doc, const std::string& key, const std::string& second,
                    const std::set<std::string>& allowed, Each each) const {
    const YAML::Node list = doc[key];
    if (!list.IsDefined()) throwAt(path, key + ": missing");
    if (!list.IsSequence() || list.size() == 0) fail(list, key + ": expected a non-empty list");
    std::vector<std::string> labels;
    for (size_t i = 0; i < list.size(); ++i) {
      const YAML::Node e = list[i];
      const std::string where = key + "[" + std::to_string(i) + "]";
      if (!e.IsMap()) fail(e, where + ": expected a map with label and " + second);
      onlyKeys(e, allowed, where);
      const std::string l = label(e, where);
      if (std::find(labels.begin(), labels.end(), l) != labels.end())
        fail(e["label"], where + ".label: '" + l + "' is used twice");
      labels.push_back(l);
      each(e, where, l);
    }
  }

  std::string file(const YAML::Node& n, const std::string& what) const {
    fs::path p = scalar(n, what);
    if (p.is_relative()) p = base / p;
    p = p.lexically_normal();
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) fail(n, what + ": no such file " + p.string());
    return p.string();
  }
};

}  // namespace

Matrix loadMatrix(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throwAt(path, "no such matrix file");
  if (fs::is_directory(path, ec)) throwAt(path, "is a folder, not a matrix file");
  YAML::Node doc;
  doc = loadYamlFile(path);  // duplicate keys, alias bombs and deep nesting are errors
  if (!doc.IsMap()) throwAt(path, "a matrix must be a map with pipelines, sequences and seeds", lineOf(doc));
  Reader r{path, fs::absolute(path).parent_path()};
  r.onlyKeys(doc, {"name", "seeds", "seed_key", "sequences", "pipelines"}, "matrix");

  Matrix m;
  m.path = path;
  if (doc["name"].IsDefined()) {
    m.name = r.folderSafe(doc["name"], "name");
  } else {  // the file's stem names the default bench folder: the same rule
    m.name = fs::path(path).stem().string();
    static const std::regex ok("[A-Za-z0-9_.-]+");
    if (!std::regex_match(m.name, ok) || m.name == "." || m.name == "..")
      throwAt(path,
              "the matrix has no name and its file name is not a folder-safe name: add name: (letters, "
              "digits, _ . -)");
  }
  if (doc["seed_key"].IsDefined()) m.seed_key = r.scalar(doc["seed_key"], "seed_key");

  const YAML::Node seeds = doc["seeds"];
  if (!seeds.IsDefined()) throwAt(path, "seeds: missing (a list of integers, e.g. [42, 1, 2])");
  if (!seeds.IsSequence() || seeds.size() == 0) r.fail(seeds, "seeds: expected a non-empty list of integers");
  for (const auto& s : seeds) {
    int64_t v = 0;
    try {
      v = s.as<int64_t>();
    } catch (const YAML::Exception&) {
      r.fail(s, "seeds: '" + (s.IsScalar() ? s.Scalar() : std::string("?")) + "' is not an integer");
    }
    if (std::find(m.seeds.begin(), m.seeds.end(), v) != m.seeds.end())
      r.fail(s, "seeds: " + std::to_string(v) + " is listed twice");
    m.seeds.push_back(v);
  }

  r.labelledList(doc, "sequences", "sequence", {"label", "sequence", "root", "set"},
                 [&](const YAML::Node& e, const std::string& where, const std::string& label) {
                   SequenceEntry s;
                   s.label = label;
                   if (!e["sequence"].IsDefined())
                     r.fail(e, where + ": 'sequence' is missing (a KITTI sequence or synth preset)");
                   s.sets.push_back("dataset.sequence=\"" + r.scalar(e["sequence"], where + ".sequence") + "\"");
                   if (e["root"].IsDefined()) {
                     fs::path root = r.scalar(e["root"], where + ".root");
                     if (root.is_relative()) root = r.base / root;
                     s.sets.push_back("dataset.root=\"" + root.lexically_normal().string() + "\"");
                   }
                   for (auto& x : r.sets(e, where)) s.sets.push_back(x);
                   m.sequences.push_back(s);
                 });

  r.labelledList(doc, "pipelines", "file", {"label", "file", "set", "sequences", "score"},
                 [&](const YAML::Node& e, const std::string& where, const std::string& label) {
                   PipelineEntry p;
                   p.label = label;
                   if (!e["file"].IsDefined()) r.fail(e, where + ": 'file' is missing (a pipeline YAML)");
                   p.file = r.file(e["file"], where + ".file");
                   p.sets = r.sets(e, where);
                   if (e["sequences"].IsDefined()) {
                     const YAML::Node only = e["sequences"];
                     if (!only.IsSequence() || only.size() == 0)
                       r.fail(only, where + ".sequences: expected a non-empty list of sequence labels");
                     for (const auto& l : only) {
                       const std::string s = r.scalar(l, where + ".sequences");
                       bool known = false;
                       for (const auto& q : m.sequences) known |= q.label == s;
                       if (!known) r.fail(l, where + ".sequences: no sequence is labelled '" + s + "'");
                       p.sequences.push_back(s);
                     }
                   }
                   if (e["score"].IsDefined()) {
                     const YAML::Node steps = e["score"];
                     std::string known;
                     for (const auto& k : kScoreSteps) known += (known.empty() ? "" : ", ") + k;
                     if (!steps.IsSequence() || steps.size() == 0)
                       r.fail(steps, where + ".score: expected a list of scoring steps (" + known + ")");
                     for (const auto& n : steps) {
                       const std::string step = r.scalar(n, where + ".score");
                       if (std::find(kScoreSteps.begin(), kScoreSteps.end(), step) == kScoreSteps.end())
                         r.fail(n, where + ".score: unknown step '" + step + "' (known: " + known + ")");
                       if (std::find(p.score.begin(), p.score.end(), step) != p.score.end())
                         r.fail(n, where + ".score: '" + step + "' is listed twice");
                       p.score.push_back(step);
                     }
                   }
                   m.pipelines.push_back(p);
                 });

  // Every cell's pipeline must load with its overrides and name plugins that exist with valid settings.
  registry::Registry registry;
  bool scanned = false;
  for (size_t i = 0; i < m.pipelines.size(); ++i) {
    const PipelineEntry& p = m.pipelines[i];
    for (const auto& s : m.sequences) {
      if (!p.sequences.empty() && std::find(p.sequences.begin(), p.sequences.end(), s.label) == p.sequences.end())
        continue;
      std::vector<std::string> sets = s.sets;
      sets.insert(sets.end(), p.sets.begin(), p.sets.end());
      sets.push_back(m.seed_key + "=" + std::to_string(m.seeds.front()));
      try {
        pipeline::PipelineSpec spec = pipeline::loadPipeline(p.file, sets);
        if (!scanned) {
          for (const auto& extra : spec.plugin_paths) registry.addSearchPath(extra);
          scanned = true;
        }
        std::vector<std::string> ids;  // only the libraries the cell names are opened
        for (const auto& [slot_name, slot] : spec.slots)
          if (!slot.plugin_id.empty()) ids.push_back(slot.plugin_id);
        registry.loadFor(ids);
        pipeline::resolvePlugins(spec, registry);
      } catch (const Error& e) {
        r.fail(doc["pipelines"][i], "pipeline '" + p.label + "' on sequence '" + s.label + "': " + e.what());
      }
    }
  }
  return m;
}

std::vector<Cell> makeCells(const Matrix& m, const std::string& out_dir) {
  (void)out_dir;
  std::vector<Cell> cells;
  for (int64_t seed : m.seeds)
    for (const auto& p : m.pipelines)
      for (const auto& s : m.sequences) {
        if (!p.sequences.empty() && std::find(p.sequences.begin(), p.sequences.end(), s.label) == p.sequences.end())
          continue;
        Cell c;
        c.index = static_cast<int>(cells.size());
        c.pipeline = p.label;
        c.sequence = s.label;
        c.seed = seed;
        c.dir = "runs/" + p.label + "/" + s.label + "/seed" + std::to_string(seed);
        c.args = {"run", p.file, "--quiet"};
        for (const auto& x : s.sets) c.args.insert(c.args.end(), {"--set", x});
        for (const auto& x : p.sets) c.args.insert(c.args.end(), {"--set", x});
        c.args.insert(c.args.end(), {"--set", m.seed_key + "=" + std::to_string(seed)});
        c.score = p.score;
        cells.push_back(c);
      }
  return cells;
}

bool cellFinished(const std::string& run_dir) {
  std::ifstream in(fs::path(run_dir) / "summary.json");
  if (!in) return false;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    // A run stopped by a signal writes its summary too, marked interrupted: not finished; nor is a run
    // whose status says it failed.
    if (j.is_object() && j.contains("status") && j["status"] != "completed") return false;
    return j.is_object() && j.contains("frames") && j["frames"].is_number() && j.contains("tracked") &&
           !j.value("interrupted", false);
  } catch (const nlohmann::json::exception&) {
    return false;
  }
}

}  // namespace beslam::bench
