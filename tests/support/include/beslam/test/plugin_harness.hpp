// Test helper: loads one plugin library through the host's registry and builds create infos whose
// configuration holds every schema key (defaults from the schema, overridden by the test's settings),
// the way the pipeline hands them over.
#pragma once

#include <deque>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "beslam/registry/instance.hpp"
#include "beslam/registry/registry.hpp"

namespace beslam::test {

class PluginHarness {
 public:
  explicit PluginHarness(const std::string& library) : log(BESLAM_LOG_ERROR) { registry.loadLibrary(library); }

  const registry::Plugin& plugin(const std::string& id) const { return registry.find(id); }

  // settings: key -> YAML-like text ("0.5", "true", "[1, 2]", "abc").
  const std::vector<beslam_config_value>& config(const std::string& id,
                                                 const std::map<std::string, std::string>& settings) {
    const registry::Plugin& p = registry.find(id);
    values_.emplace_back();
    auto& out = values_.back();
    for (const auto& [key, value] : settings) {
      bool known = false;
      for (const auto& f : p.fields) known = known || f.key == key;
      if (!known) throw std::invalid_argument("test: plugin " + id + " has no setting " + key);
    }
    for (const registry::ConfigField& f : p.fields) {
      auto it = settings.find(f.key);
      std::string text = it != settings.end() ? it->second : f.default_value;
      if (text.size() >= 2 && text.front() == '"' && text.back() == '"') text = text.substr(1, text.size() - 2);
      keys_.push_back(f.key);
      beslam_config_value v{};
      v.key = keys_.back().c_str();
      v.type = f.type;
      switch (f.type) {
        case BESLAM_CONFIG_BOOL:
          v.number = (text == "true") ? 1 : 0;
          break;
        case BESLAM_CONFIG_INT:
        case BESLAM_CONFIG_DOUBLE:
          v.number = std::stod(text);
          break;
        case BESLAM_CONFIG_DOUBLE_LIST: {
          std::vector<double> list;
          std::string inner = text;
          for (char& c : inner)
            if (c == '[' || c == ']' || c == ',') c = ' ';
          std::istringstream ss(inner);
          for (double d; ss >> d;) list.push_back(d);
          lists_.push_back(list);
          v.list = lists_.back().data();
          v.list_size = lists_.back().size();
          break;
        }
        default:
          texts_.push_back(text);
          v.text = texts_.back().c_str();
      }
      out.push_back(v);
    }
    return out;
  }

  beslam_create_info info(const std::vector<beslam_config_value>& config, const std::string& output_dir = "") {
    out_dirs_.push_back(output_dir);
    beslam_create_info info{};
    info.struct_size = sizeof(info);
    info.host = log.host();
    info.config = config.data();
    info.config_count = static_cast<uint32_t>(config.size());
    info.camera.struct_size = sizeof(beslam_camera);
    info.camera.width = 1242;
    info.camera.height = 375;
    info.camera.fx = info.camera.fy = 721.5;
    info.camera.cx = 609.6;
    info.camera.cy = 172.9;
    info.output_dir = out_dirs_.back().c_str();
    return info;
  }

  static beslam_frame frame(int64_t index, double timestamp) {
    beslam_frame f{};
    f.struct_size = sizeof(f);
    f.index = index;
    f.timestamp = timestamp;
    return f;
  }

  registry::Registry registry;
  registry::HostLog log;

 private:
  std::deque<std::vector<beslam_config_value>> values_;
  std::deque<std::string> keys_, texts_, out_dirs_;
  std::deque<std::vector<double>> lists_;
};

}  // namespace beslam::test
