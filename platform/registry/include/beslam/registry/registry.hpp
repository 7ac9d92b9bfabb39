// The plugin registry: finds plugin libraries, checks them against the ABI and lists their plugins.
//
// Search paths, in order: those added by the caller (pipeline `plugin_paths`, --plugin-path), the
// colon-separated BESLAM_PLUGIN_PATH environment variable, then the folders beside the executable
// (<exe>/../lib/beslam/plugins: the build tree and the install prefix). A library is checked before any
// of its code runs (a regular file with an ELF header, not writable by group or others, in a folder not
// writable by group or others; the entry symbols must exist), then its ABI major version, then each
// descriptor (struct size, kind, id, create/destroy, the kind's function table). Anything wrong is a
// beslam::Error naming the library file (or folder) and the cause; scan() collects such errors instead of
// throwing. A Registry must outlive every instance created from its plugins.
//
// What runs: loadFor() opens only <folder>/<id>.so for the ids it is given (an id is checked against
// [a-z0-9_]+ before any path is formed), never every library of a folder; a library that provides several
// plugins is reached through a file named after each id (a symlink: beslam_add_plugin's ALSO_PROVIDES).
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
bool isPluginId(const std::string& id);  // [a-z0-9_]+

class Registry {
 public:
  Registry();
  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  void addSearchPath(const std::string& folder);
  // Lets search folders and plugin files that group or others can write to be used (refused by default:
  // anyone who can write there chooses the code the host runs). --allow-writable-plugin-dirs.
  void allowWritable(bool allow);
  std::vector<std::string> searchPaths() const;  // the effective list, in order

  // Loads every shared library (*.so) in the search paths, to list them (`beslam plugins`); later
  // duplicates of an id are reported. A writable folder or file is a problem, and is not opened.
  void scan();
  // Loads what a pipeline needs and nothing else: for each id, <folder>/<id>.so of the first search
  // folder holding one (a library that does not provide the id is a problem find() names). Throws
  // beslam::Error for an id that is not [a-z0-9_]+ (before any path is formed) and for a writable folder
  // or library met on the way. An id found nowhere is left for find() to report.
  void loadFor(const std::vector<std::string>& ids);
  // Loads one library explicitly; throws beslam::Error naming the file on any problem.
  void loadLibrary(const std::string& path);
  // The library files loaded so far, in load order (as given, not resolved through symlinks).
  std::vector<std::string> loadedFiles() const;

  const std::vector<Plugin>& plugins() const;
  const std::vector<std::string>& problems() const;  // "FILE: cause" for libraries scan() refused
  // Throws beslam::Error listing the known ids of that kind when id is unknown or of another kind.
  const Plugin& find(const std::string& id, int32_t kind = 0) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace beslam::registry
