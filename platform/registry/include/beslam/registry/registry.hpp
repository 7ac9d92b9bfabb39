// The plugin registry: finds plugin libraries, checks them against the ABI and lists their plugins.
//
// Search paths, in order: those added by the caller (pipeline `plugin_paths`, --plugin-path), the
// colon-separated BESLAM_PLUGIN_PATH environment variable, then the folders beside the executable
// (<exe>/../lib/beslam/plugins: the build tree and the install prefix). A library is checked before any
// of its code runs (the entry symbols must exist), then its ABI major version, then each descriptor
// (struct size, kind, id, create/destroy, the kind's function table). Anything wrong is a
// beslam::Error naming the library file and the cause; scan() collects such errors instead of throwing.
// A Registry must outlive every instance created from its plugins.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "beslam/plugin.h"

namespace beslam::registry {

struct ConfigField {
  std::string key;
  int32_t type = 0;
  bool required = false;
  std::string default_value;            // YAML text
  double min_value = 1, max_value = 0;  // min > max: unbounded
  std::string choices;                  // "a|b|c" or empty
  std::string doc;
};

struct Plugin {
  std::string id, name, description;
  int32_t kind = 0;
  std::string version;       // "major.minor.patch"
  uint32_t abi_version = 0;  // (major << 16) | minor the plugin was built with
  std::string library_path;
  std::vector<ConfigField> fields;
  beslam_plugin_descriptor descriptor{};  // the host's zero-filled copy
  const void* functions = nullptr;        // the kind's table as the plugin provides it
  uint32_t functions_size = 0;            // its struct_size
};

const char* kindName(int32_t kind);                   // "detector", "motion_checker", ...
int32_t kindFromName(const std::string& name);        // 0 if unknown
const char* configTypeName(int32_t type);             // "bool", "int", ...
ConfigField fieldOf(const beslam_config_field& raw);  // a C schema entry as the host keeps it
const char* statusName(beslam_status status);

class Registry {
 public:
  Registry();
  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  void addSearchPath(const std::string& folder);
  std::vector<std::string> searchPaths() const;  // the effective list, in order

  // Loads every shared library (*.so) in the search paths; later duplicates of an id are reported.
  void scan();
  // Loads what a pipeline needs, quickly: for each id, the first search path holding a library named
  // after it (<id>.so, as every built-in plugin is) gives it; if any id is not found that way (a
  // library named otherwise, or providing several plugins), a full scan() follows. A library named
  // after a plugin is therefore preferred to one of another name earlier in the path. Loading every
  // library costs 0.3-0.5 s of start-up (their dependencies: PCL, OpenCV DNN); `beslam plugins` and
  // anything listing or checking all plugins still call scan().
  void loadFor(const std::vector<std::string>& ids);
  // Loads one library explicitly; throws beslam::Error naming the file on any problem.
  void loadLibrary(const std::string& path);

  const std::vector<Plugin>& plugins() const;
  const std::vector<std::string>& problems() const;  // "FILE: cause" for libraries scan() refused
  // Throws beslam::Error listing the known ids of that kind when id is unknown or of another kind.
  const Plugin& find(const std::string& id, int32_t kind = 0) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace beslam::registry
