// SynthConfig: YAML reading with strict validation, writing, and the built-in presets.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/yaml_load.hpp"
#include "beslam/common/yaml_set.hpp"
#include "beslam/sim/synth.hpp"
#include "presets.hpp"

namespace beslam::sim {
namespace {

// Visits every known key; `bind` reads (when reading) or writes (when writing) one value.
class Binder {
 public:
  virtual ~Binder() = default;
  virtual void i(const std::string& key, int& v, int lo, int hi) = 0;
  virtual void u64(const std::string& key, std::uint64_t& v) = 0;
  virtual void d(const std::string& key, double& v, double lo, double hi) = 0;
  virtual void b(const std::string& key, bool& v) = 0;
  virtual void s(const std::string& key, std::string& v, const std::vector<std::string>& allowed) = 0;
};

// Every key of platform/sim/config_keys.json, in its order: x.d("camera.fx", c.camera.fx, 10.0, 1e5), ...
void bindAll(Binder& x, SynthConfig& c) {
#include "config_keys.inc"
}

// Looks a dotted key up without modifying the tree (lookups go through const nodes); false when the
// key is absent or null.
bool findKey(const YAML::Node& root, const std::string& key, YAML::Node& out) {
  std::vector<YAML::Node> chain{root};
  std::size_t start = 0;
  while (true) {
    const auto dot = key.find('.', start);
    const std::string part = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    const YAML::Node& here = chain.back();
    if (!here.IsMap()) return false;
    const YAML::Node child = here[part];
    if (!child.IsDefined() || child.IsNull()) return false;
    if (dot == std::string::npos) {
      out = child;
      return true;
    }
    chain.push_back(child);
    start = dot + 1;
  }
}

std::string describe(const YAML::Node& n) {
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  if (n.IsMap()) return "a map";
  if (n.IsSequence()) return "a list";
  return "nothing";
}

class Reader : public Binder {
 public:
  Reader(const YAML::Node& root, std::string source) : root_(root), source_(std::move(source)) {}
  std::set<std::string> known;

  void i(const std::string& key, int& v, int lo, int hi) override {
    YAML::Node n;
    if (!get(key, n)) return;
    long long x = 0;
    if (!n.IsScalar() || !parseInt(n.Scalar(), x)) fail(key, "expected an integer, got " + describe(n));
    if (x < lo || x > hi)
      fail(key, n.Scalar() + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    v = static_cast<int>(x);
  }
  void u64(const std::string& key, std::uint64_t& v) override {
    YAML::Node n;
    if (!get(key, n)) return;
    long long x = 0;
    if (!n.IsScalar() || !parseInt(n.Scalar(), x) || x < 0)
      fail(key, "expected a non-negative integer, got " + describe(n));
    v = static_cast<std::uint64_t>(x);
  }
  void d(const std::string& key, double& v, double lo, double hi) override {
    YAML::Node n;
    if (!get(key, n)) return;
    double x = 0;
    if (!n.IsScalar() || !parseDouble(n.Scalar(), x)) fail(key, "expected a number, got " + describe(n));
    if (!(x >= lo && x <= hi)) {
      std::ostringstream o;
      o << n.Scalar() << " is out of range [" << lo << ", " << hi << "]";
      fail(key, o.str());
    }
    v = x;
  }
  void b(const std::string& key, bool& v) override {
    YAML::Node n;
    if (!get(key, n)) return;
    const std::string s = n.IsScalar() ? n.Scalar() : "";
    if (s == "true" || s == "True" || s == "yes" || s == "on")
      v = true;
    else if (s == "false" || s == "False" || s == "no" || s == "off")
      v = false;
    else
      fail(key, "expected true or false, got " + describe(n));
  }
  void s(const std::string& key, std::string& v, const std::vector<std::string>& allowed) override {
    YAML::Node n;
    if (!get(key, n)) return;
    if (!n.IsScalar()) fail(key, "expected a string, got " + describe(n));
    if (!allowed.empty()) {
      bool ok = false;
      std::string list;
      for (const auto& a : allowed) {
        ok = ok || a == n.Scalar();
        list += (list.empty() ? "" : ", ") + a;
      }
      if (!ok) fail(key, "'" + n.Scalar() + "' is not one of: " + list);
    }
    v = n.Scalar();
  }

  void checkUnknown(const YAML::Node& node, const std::string& prefix) {
    if (!node.IsDefined() || node.IsNull()) return;
    if (!node.IsMap())
      throwAt(source_, (prefix.empty() ? std::string("top level") : "key '" + prefix + "'") + ": expected a map, got " +
                           describe(node));
    for (const auto& kv : node) {
      const std::string name = kv.first.as<std::string>();
      const std::string full = prefix.empty() ? name : prefix + "." + name;
      bool isPrefix = false;
      for (const auto& k : known) isPrefix = isPrefix || k.rfind(full + ".", 0) == 0;
      if (known.count(full)) continue;
      if (isPrefix) {
        checkUnknown(kv.second, full);
        continue;
      }
      throwAt(source_, "unknown key '" + full + "'");
    }
  }

 private:
  bool get(const std::string& key, YAML::Node& n) {
    known.insert(key);
    return findKey(root_, key, n);
  }
  [[noreturn]] void fail(const std::string& key, const std::string& cause) {
    throwAt(source_, "key '" + key + "': " + cause);
  }
  static bool parseInt(const std::string& s, long long& out) {
    if (s.empty()) return false;
    std::size_t pos = 0;
    try {
      out = std::stoll(s, &pos, 10);
    } catch (...) {
      return false;
    }
    return pos == s.size();
  }
  static bool parseDouble(const std::string& s, double& out) {
    if (s.empty()) return false;
    std::size_t pos = 0;
    try {
      out = std::stod(s, &pos);
    } catch (...) {
      return false;
    }
    return pos == s.size() && std::isfinite(out);
  }
  YAML::Node root_;
  std::string source_;
};

// Emits keys in bindAll's order (each section's keys are contiguous), numbers with 10 significant
// digits, strings double-quoted so "00" stays a string for any YAML reader.
class Writer : public Binder {
 public:
  YAML::Emitter e;
  Writer() { e << YAML::BeginMap; }
  std::string finish() {
    if (!section_.empty()) e << YAML::EndMap;
    e << YAML::EndMap;
    return std::string(e.c_str()) + "\n";
  }
  void i(const std::string& k, int& v, int, int) override { key(k) << YAML::Value << v; }
  void u64(const std::string& k, std::uint64_t& v) override { key(k) << YAML::Value << v; }
  void d(const std::string& k, double& v, double, double) override {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.10g", v);
    key(k) << YAML::Value << std::string(buf);
  }
  void b(const std::string& k, bool& v) override { key(k) << YAML::Value << v; }
  void s(const std::string& k, std::string& v, const std::vector<std::string>&) override {
    key(k) << YAML::Value << YAML::DoubleQuoted << v;
  }

 private:
  YAML::Emitter& key(const std::string& full) {
    const auto dot = full.find('.');
    const std::string section = dot == std::string::npos ? "" : full.substr(0, dot);
    if (section != section_) {
      if (!section_.empty()) e << YAML::EndMap;
      if (!section.empty()) e << YAML::Key << section << YAML::Value << YAML::BeginMap;
      section_ = section;
    }
    e << YAML::Key << (dot == std::string::npos ? full : full.substr(dot + 1));
    return e;
  }
  std::string section_;
};

}  // namespace

SynthConfig synthConfigFromYaml(const YAML::Node& root, const std::string& source) {
  SynthConfig c;
  Reader reader(root, source);
  bindAll(reader, c);
  reader.checkUnknown(root, "");
  if (c.world.building_max_height < c.world.building_min_height)
    throwAt(source, "key 'world.building_max_height': smaller than world.building_min_height");
  if (c.objects.driving_speed_kmh_max < c.objects.driving_speed_kmh_min)
    throwAt(source, "key 'objects.driving_speed_kmh_max': smaller than objects.driving_speed_kmh_min");
  if (c.lidar.fov_down_deg >= c.lidar.fov_up_deg)
    throwAt(source, "key 'lidar.fov_down_deg': must be below lidar.fov_up_deg");
  if (c.sequence.empty() || c.sequence.find_first_not_of("0123456789") != std::string::npos)
    throwAt(source, "key 'sequence': expected digits such as \"00\", got '" + c.sequence + "'");
  if (c.objects.stop_and_go > 0 && !c.world.parking_lanes)
    throwAt(source, "key 'objects.stop_and_go': stop-and-go cars need world.parking_lanes: true");
  const double r = c.world.corner_radius;
  const double half = c.world.lanes_per_direction * c.world.lane_width + (c.world.parking_lanes ? 2.2 : 0.0);
  if (r < half + 2.0)
    throwAt(source, "key 'world.corner_radius': must be at least the road half width + 2 m (" +
                        std::to_string(half + 2.0) + ")");
  if (2 * r > std::min(c.world.block_x, c.world.block_y) - 10.0)
    throwAt(source, "key 'world.corner_radius': too large for the block size");
  return c;
}

SynthConfig loadSynthConfig(const std::string& path, const std::vector<std::string>& set_overrides) {
  YAML::Node root;
  try {
    root = loadYamlFile(path);  // duplicate keys, alias bombs and deep nesting are errors
  } catch (const YAML::Exception& e) {
    throwAt(path, "invalid YAML: " + e.msg, e.mark.line + 1);
  }
  if (!root.IsDefined() || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  for (const auto& assignment : set_overrides) applySetOverride(root, assignment);
  return synthConfigFromYaml(root, path);
}

std::string synthConfigToYaml(const SynthConfig& config) {
  SynthConfig copy = config;
  Writer writer;
  bindAll(writer, copy);
  return writer.finish();
}

std::vector<std::string> presetNames() {
  std::vector<std::string> names;
  for (const auto& p : detail::presetTexts()) names.push_back(p.first);
  return names;
}

SynthConfig presetConfig(const std::string& name) {
  for (const auto& p : detail::presetTexts())
    if (p.first == name) return synthConfigFromYaml(YAML::Load(p.second), "preset " + name);
  std::string list;
  for (const auto& n : presetNames()) list += (list.empty() ? "" : ", ") + n;
  throw Error("synth preset '" + name + "': unknown (known: " + list + ")");
}

const char* behaviourName(Behaviour b) {
  switch (b) {
    case Behaviour::Parked:
      return "parked";
    case Behaviour::Driving:
      return "driving";
    case Behaviour::StopAndGo:
      return "stop_and_go";
    case Behaviour::Pedestrian:
      return "pedestrian";
  }
  return "?";
}

}  // namespace beslam::sim
