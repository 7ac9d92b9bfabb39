#include "beslam/registry/registry.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <boost/dll/library_info.hpp>
#include <boost/dll/runtime_symbol_info.hpp>
#include <boost/dll/shared_library.hpp>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "beslam/common/error.hpp"

namespace fs = std::filesystem;

namespace beslam::registry {

namespace {

// The name of `code` in a table of {code, name} pairs, or `fallback`.
struct CodeName {
  int32_t code;
  const char* name;
};
template <std::size_t N>
const char* nameOf(int32_t code, const CodeName (&names)[N], const char* fallback) {
  for (const CodeName& n : names)
    if (n.code == code) return n.name;
  return fallback;
}

}  // namespace

const char* kindName(int32_t kind) {
  static constexpr CodeName kNames[] = {{BESLAM_KIND_DETECTOR, "detector"},
                                        {BESLAM_KIND_MOTION_CHECKER, "motion_checker"},
                                        {BESLAM_KIND_MASK_GENERATOR, "mask_generator"},
                                        {BESLAM_KIND_RECONSTRUCTOR, "reconstructor"},
                                        {BESLAM_KIND_BACKEND, "backend"}};
  return nameOf(kind, kNames, "unknown");
}

int32_t kindFromName(const std::string& name) {
  for (int32_t k = BESLAM_KIND_DETECTOR; k <= BESLAM_KIND_BACKEND; ++k)
    if (name == kindName(k)) return k;
  return 0;
}

const char* configTypeName(int32_t type) {
  static constexpr CodeName kNames[] = {
      {BESLAM_CONFIG_BOOL, "bool"},     {BESLAM_CONFIG_INT, "int"},   {BESLAM_CONFIG_DOUBLE, "double"},
      {BESLAM_CONFIG_STRING, "string"}, {BESLAM_CONFIG_PATH, "path"}, {BESLAM_CONFIG_DOUBLE_LIST, "list of double"}};
  return nameOf(type, kNames, "unknown");
}

const char* statusName(beslam_status status) {
  static constexpr CodeName kNames[] = {{BESLAM_OK, "ok"},
                                        {BESLAM_ERROR_INVALID_ARGUMENT, "invalid argument"},
                                        {BESLAM_ERROR_INVALID_CONFIG, "invalid configuration"},
                                        {BESLAM_ERROR_RUNTIME, "runtime error"},
                                        {BESLAM_ERROR_OUT_OF_MEMORY, "out of memory"},
                                        {BESLAM_ERROR_UNSUPPORTED, "unsupported"},
                                        {BESLAM_ERROR_INTERNAL, "internal error"}};
  return nameOf(status, kNames, "unknown status");
}

namespace {

// The smallest struct sizes ABI 1.0 defines: anything shorter is refused.
constexpr uint32_t kMinDescriptorSize = offsetof(beslam_plugin_descriptor, functions) + sizeof(void*);
constexpr uint32_t kMinFieldSize = offsetof(beslam_config_field, doc) + sizeof(const char*);

uint32_t minTableSize(int32_t kind) {
  switch (kind) {
    case BESLAM_KIND_DETECTOR:
      return sizeof(beslam_detector_v1);
    case BESLAM_KIND_MOTION_CHECKER:  // ABI 1.7's world_moved is optional
      return offsetof(beslam_motion_checker_v1, world_moved);
    case BESLAM_KIND_MASK_GENERATOR:
      return sizeof(beslam_mask_generator_v1);
    case BESLAM_KIND_RECONSTRUCTOR:  // ABI 1.3's finish is optional
      return offsetof(beslam_reconstructor_v1, finish);
    case BESLAM_KIND_BACKEND:  // ABI 1.4's prepare is optional
      return offsetof(beslam_backend_v1, prepare);
    default:
      return 0;
  }
}

// True when every named function pointer of the kind's table `Table` is set.
template <class Table, class... Fns>
bool allSet(const void* table, Fns Table::*... fns) {
  const auto* t = static_cast<const Table*>(table);
  return ((t->*fns != nullptr) && ...);
}

// Every function pointer of a kind's table must be set (ABI 1.0 has no optional calls).
bool tableComplete(int32_t kind, const void* table) {
  switch (kind) {
    case BESLAM_KIND_DETECTOR:
      return allSet<beslam_detector_v1>(table, &beslam_detector_v1::detect);
    case BESLAM_KIND_MOTION_CHECKER:
      return allSet<beslam_motion_checker_v1>(table, &beslam_motion_checker_v1::classify);
    case BESLAM_KIND_MASK_GENERATOR:
      return allSet<beslam_mask_generator_v1>(table, &beslam_mask_generator_v1::generate);
    case BESLAM_KIND_RECONSTRUCTOR:
      return allSet<beslam_reconstructor_v1>(table, &beslam_reconstructor_v1::reconstruct);
    case BESLAM_KIND_BACKEND:
      return allSet<beslam_backend_v1>(table, &beslam_backend_v1::predict_pose, &beslam_backend_v1::track,
                                       &beslam_backend_v1::add_landmarks, &beslam_backend_v1::finish,
                                       &beslam_backend_v1::trajectory, &beslam_backend_v1::map_points);
    default:
      return false;
  }
}

bool validId(const char* id) { return id != nullptr && isPluginId(id); }

std::string str(const char* s) { return s ? s : ""; }

// A name as it may be printed in one line: control characters escaped, at most 80 characters.
std::string printable(const std::string& text) {
  std::string out;
  for (unsigned char c : text.substr(0, 80)) {
    if (c < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += static_cast<char>(c);
    }
  }
  return text.size() > 80 ? out + "..." : out;
}

constexpr const char* kAllowWritable = "--allow-writable-plugin-dirs";

// Empty when group and others cannot write to `path` (followed through symlinks) or it does not exist,
// else why it is refused.
std::string writableProblem(const fs::path& path, const char* what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return {};
  if ((st.st_mode & (S_IWGRP | S_IWOTH)) == 0) return {};
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
  return path.string() + ": " + what + " is writable by " + ((st.st_mode & S_IWOTH) ? "others" : "its group") +
         " (mode " + mode + "), so anyone who can write there chooses the code beslam runs; refused (chmod go-w " +
         path.string() + ", or pass " + kAllowWritable + ")";
}

}  // namespace

bool isPluginId(const std::string& id) {
  if (id.empty()) return false;
  for (char c : id)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  return true;
}

struct Registry::Impl {
  std::vector<std::string> extra_paths;
  std::vector<boost::dll::shared_library> libraries;  // kept loaded as long as the registry lives
  std::vector<Plugin> plugins;
  std::vector<std::string> problems;
  std::map<std::string, std::string> loaded_files;  // canonical path -> path
  std::vector<std::string> load_order;              // paths as given, in load order
  bool allow_writable = false;

  void load(const std::string& path);
  // Throws when the library `path` may not be loaded: it (through a symlink, its target) or a folder
  // holding it is writable by group or others, unless allowed.
  void checkFile(const std::string& path) const {
    if (allow_writable) return;
    std::error_code ec;
    const fs::path canonical = fs::canonical(path, ec), given = fs::absolute(path, ec);
    for (const auto& [where, what] : {std::pair<fs::path, const char*>{canonical, "plugin library"},
                                      {canonical.parent_path(), "plugin folder"},
                                      {given.parent_path(), "plugin folder"}})
      if (std::string problem = writableProblem(where, what); !problem.empty()) throw Error(problem);
  }
  // Throws when `folder` may not be searched (writable by group or others, unless allowed).
  void checkFolder(const std::string& folder) const {
    if (allow_writable) return;
    if (const std::string problem = writableProblem(folder, "plugin folder"); !problem.empty()) throw Error(problem);
  }
  void addProblem(const std::string& problem) {  // once: loadFor() and a scan() after it may meet the same file
    if (std::find(problems.begin(), problems.end(), problem) == problems.end()) problems.push_back(problem);
  }
};

Registry::Registry() : impl_(std::make_unique<Impl>()) {}
Registry::~Registry() {
  impl_->plugins.clear();  // descriptors point into the libraries: drop them first
}

void Registry::addSearchPath(const std::string& folder) { impl_->extra_paths.push_back(folder); }
void Registry::allowWritable(bool allow) { impl_->allow_writable = allow; }
std::vector<std::string> Registry::loadedFiles() const { return impl_->load_order; }

std::vector<std::string> Registry::searchPaths() const {
  std::vector<std::string> paths = impl_->extra_paths;
  if (const char* env = std::getenv("BESLAM_PLUGIN_PATH")) {
    std::stringstream ss(env);
    std::string item;
    while (std::getline(ss, item, ':'))
      if (!item.empty()) paths.push_back(item);
  }
  boost::system::error_code ec;
  const auto exe = boost::dll::program_location(ec);
  if (!ec) {
    const fs::path prefix = fs::path(exe.string()).parent_path().parent_path();
    paths.push_back((prefix / "lib" / "beslam" / "plugins").string());
#ifdef BESLAM_INSTALL_LIBDIR
    paths.push_back((prefix / BESLAM_INSTALL_LIBDIR / "beslam" / "plugins").string());
#endif
  }
  std::vector<std::string> unique;
  for (const auto& p : paths)
    if (std::find(unique.begin(), unique.end(), p) == unique.end()) unique.push_back(p);
  return unique;
}

void Registry::scan() {
  for (const std::string& folder : searchPaths()) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) continue;
    try {
      impl_->checkFolder(folder);
    } catch (const Error& e) {
      impl_->addProblem(e.what());
      continue;
    }
    std::vector<fs::path> files;
    const fs::path here = fs::canonical(folder, ec);
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
      if (!entry.is_regular_file() || entry.path().extension() != ".so") continue;
      std::error_code link_ec;  // an alias (<id>.so -> a library beside it) lists its library once, by its name
      if (entry.is_symlink() && fs::canonical(entry.path(), link_ec).parent_path() == here) continue;
      files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& file : files) {
      try {
        impl_->load(file.string());
      } catch (const Error& e) {
        impl_->addProblem(e.what());
      }
    }
  }
}

void Registry::loadFor(const std::vector<std::string>& ids) {
  const auto provided = [this](const std::string& id) {
    return std::any_of(impl_->plugins.begin(), impl_->plugins.end(), [&](const Plugin& p) { return p.id == id; });
  };
  for (const std::string& id : ids)  // before any path is formed from one
    if (!isPluginId(id))
      throw Error("plugin id '" + printable(id) + "' is not a plugin id (accepted: [a-z0-9_]+, e.g. backend_orb)");
  const std::vector<std::string> folders = searchPaths();
  for (const std::string& folder : folders) {
    std::error_code ec;
    if (fs::is_directory(folder, ec)) impl_->checkFolder(folder);
  }
  for (const std::string& id : ids) {
    for (const std::string& folder : folders) {
      if (provided(id)) break;
      std::error_code ec;
      const fs::path file = fs::path(folder) / (id + ".so");
      if (!fs::exists(file, ec)) continue;
      impl_->checkFile(file.string());  // a writable library is an error, not a reason to look further
      try {
        impl_->load(file.string());
      } catch (const Error& e) {
        impl_->addProblem(e.what());
        continue;
      }
      if (!provided(id)) impl_->addProblem(file.string() + ": does not provide plugin '" + id + "'");
    }
  }
}

void Registry::loadLibrary(const std::string& path) { impl_->load(path); }

void Registry::Impl::load(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throwAt(path, "no such plugin library");
  if (!fs::is_regular_file(path, ec)) throwAt(path, "not a shared library (not a regular file)");
  const std::string canonical = fs::canonical(path, ec).string();
  if (loaded_files.count(canonical)) return;
  checkFile(path);
  {  // what is no ELF file at all gets a clear word before the ELF reader sees it
    char magic[4] = {};
    std::ifstream in(path, std::ios::binary);
    if (!in) throwAt(path, "cannot open the plugin library");
    in.read(magic, sizeof magic);
    if (in.gcount() != 4 || magic[0] != 0x7f || magic[1] != 'E' || magic[2] != 'L' || magic[3] != 'F')
      throwAt(path, "not a shared library (no ELF header; a plugin is a .so built with beslam_add_plugin)");
  }

  // Check the entry points are there before running any of the library's code.
  try {
    boost::dll::library_info info(path);
    const auto symbols = info.symbols();
    const bool has_version = std::find(symbols.begin(), symbols.end(), BESLAM_ABI_VERSION_SYMBOL) != symbols.end();
    const bool has_list = std::find(symbols.begin(), symbols.end(), BESLAM_PLUGIN_LIST_SYMBOL) != symbols.end();
    if (!has_version && !has_list)
      throwAt(path, "not a BE-SLAM plugin (no beslam_plugin_list or beslam_plugin_abi_version symbol)");
    if (!has_version) throwAt(path, "missing symbol " BESLAM_ABI_VERSION_SYMBOL);
    if (!has_list) throwAt(path, "missing symbol " BESLAM_PLUGIN_LIST_SYMBOL);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throwAt(path, std::string("not a loadable shared library: ") + e.what());
  }

  boost::dll::shared_library lib;
  try {
    lib.load(path, boost::dll::load_mode::rtld_local | boost::dll::load_mode::rtld_now);
  } catch (const std::exception& e) {
    throwAt(path, std::string("cannot load: ") + e.what());
  }
  const auto abi_version = lib.get<uint32_t()>(BESLAM_ABI_VERSION_SYMBOL)();
  const uint32_t major = abi_version >> 16, minor = abi_version & 0xffff;
  if (major != BESLAM_ABI_VERSION_MAJOR) {
    throwAt(path, "built for plugin ABI " + std::to_string(major) + "." + std::to_string(minor) +
                      ", this host speaks ABI " + std::to_string(BESLAM_ABI_VERSION_MAJOR) + "." +
                      std::to_string(BESLAM_ABI_VERSION_MINOR) + " (major versions must match)");
  }

  const beslam_plugin_descriptor* const* list = nullptr;
  uint32_t count = 0;
  const beslam_status status = lib.get<beslam_status(const beslam_plugin_descriptor* const**, uint32_t*)>(
      BESLAM_PLUGIN_LIST_SYMBOL)(&list, &count);
  if (status != BESLAM_OK) throwAt(path, std::string("beslam_plugin_list failed: ") + statusName(status));
  if (count > 0 && list == nullptr) throwAt(path, "beslam_plugin_list returned a null list");

  std::vector<Plugin> found;
  for (uint32_t i = 0; i < count; ++i) {
    const beslam_plugin_descriptor* d = list[i];
    const std::string where = "descriptor " + std::to_string(i);
    if (d == nullptr) throwAt(path, where + " is null");
    if (d->struct_size < kMinDescriptorSize)
      throwAt(path, where + ": struct_size " + std::to_string(d->struct_size) + " is smaller than ABI 1.0's " +
                        std::to_string(kMinDescriptorSize));
    Plugin p;
    std::memcpy(&p.descriptor, d, std::min<size_t>(d->struct_size, sizeof(p.descriptor)));
    const beslam_plugin_descriptor& c = p.descriptor;
    if ((c.abi_version >> 16) != BESLAM_ABI_VERSION_MAJOR)
      throwAt(path, where + ": descriptor claims ABI major " + std::to_string(c.abi_version >> 16));
    if (!validId(c.id)) throwAt(path, where + ": id '" + str(c.id) + "' is not [a-z0-9_]+");
    const std::string id = c.id;
    if (minTableSize(c.kind) == 0) throwAt(path, "plugin " + id + ": unknown kind " + std::to_string(c.kind));
    if (c.create == nullptr || c.destroy == nullptr) throwAt(path, "plugin " + id + ": create or destroy is null");
    if (c.functions == nullptr) throwAt(path, "plugin " + id + ": no function table");
    const uint32_t table_size = *static_cast<const uint32_t*>(c.functions);
    if (table_size < minTableSize(c.kind))
      throwAt(path, "plugin " + id + ": " + kindName(c.kind) + " table struct_size " + std::to_string(table_size) +
                        " is smaller than ABI 1.0's " + std::to_string(minTableSize(c.kind)));
    if (!tableComplete(c.kind, c.functions)) throwAt(path, "plugin " + id + ": a function of its table is null");
    if (c.config_field_count > 0 && (c.config_fields == nullptr || c.config_field_size < kMinFieldSize))
      throwAt(path, "plugin " + id + ": bad configuration schema (null fields or field size too small)");

    p.id = id;
    p.name = str(c.name);
    p.description = str(c.description);
    p.kind = c.kind;
    p.version =
        std::to_string(c.version_major) + "." + std::to_string(c.version_minor) + "." + std::to_string(c.version_patch);
    p.abi_version = c.abi_version;
    p.library_path = path;
    p.functions = c.functions;
    p.functions_size = table_size;
    const char* base = reinterpret_cast<const char*>(c.config_fields);
    for (uint32_t f = 0; f < c.config_field_count; ++f) {
      beslam_config_field raw{};
      std::memcpy(&raw, base + static_cast<size_t>(f) * c.config_field_size,
                  std::min<size_t>(c.config_field_size, sizeof(raw)));
      if (!validId(raw.key))
        throwAt(path, "plugin " + id + ": configuration key '" + str(raw.key) + "' is not [a-z0-9_]+");
      if (std::string(raw.key) == "plugin") throwAt(path, "plugin " + id + ": configuration key 'plugin' is reserved");
      if (raw.type < BESLAM_CONFIG_BOOL || raw.type > BESLAM_CONFIG_DOUBLE_LIST)
        throwAt(path,
                "plugin " + id + ": configuration key '" + raw.key + "' has unknown type " + std::to_string(raw.type));
      if (!raw.required && raw.default_value == nullptr)
        throwAt(path, "plugin " + id + ": configuration key '" + raw.key + "' is optional but has no default");
      p.fields.push_back(fieldOf(raw));
    }
    for (const Plugin& other : plugins)
      if (other.id == id) throwAt(path, "plugin id '" + id + "' is already provided by " + other.library_path);
    for (const Plugin& other : found)
      if (other.id == id) throwAt(path, "plugin id '" + id + "' appears twice in this library");
    found.push_back(std::move(p));
  }
  libraries.push_back(std::move(lib));
  loaded_files[canonical] = path;
  load_order.push_back(path);
  for (Plugin& p : found) plugins.push_back(std::move(p));
}

const std::vector<Plugin>& Registry::plugins() const { return impl_->plugins; }
const std::vector<std::string>& Registry::problems() const { return impl_->problems; }

const Plugin& Registry::find(const std::string& id, int32_t kind) const {
  std::string known;
  for (const Plugin& p : impl_->plugins) {
    if (p.id == id) {
      if (kind != 0 && p.kind != kind)
        throw Error("plugin '" + id + "' is a " + kindName(p.kind) + ", not a " + kindName(kind) + " (" +
                    p.library_path + ")");
      return p;
    }
    if (kind == 0 || p.kind == kind) known += (known.empty() ? "" : ", ") + p.id;
  }
  std::string message = "unknown plugin '" + printable(id) + "'";
  message += known.empty() ? std::string(" (no plugins of that kind loaded") : " (known: " + known;
  message += "; no " + printable(id) + ".so in the search path ";
  const auto paths = searchPaths();
  std::set<std::string> libraries;  // listed, not loaded: what the id may have meant
  for (size_t i = 0; i < paths.size(); ++i) {
    message += (i ? ":" : "") + paths[i];
    std::error_code ec;
    for (fs::directory_iterator it(paths[i], ec), end; !ec && it != end; it.increment(ec))
      if (it->path().extension() == ".so") libraries.insert(it->path().stem().string());
  }
  if (!libraries.empty()) {
    message += "; libraries there:";
    for (const std::string& l : libraries) message += " " + printable(l);
    message += " (each id is a file <id>.so: a symlink for a library's further plugins)";
  }
  message += ")";
  // A library refused for this reason may have been the one meant: say why each was refused.
  for (const std::string& problem : impl_->problems) message += "; refused " + problem;
  throw Error(message);
}

ConfigField fieldOf(const beslam_config_field& raw) {
  return {str(raw.key),  raw.type,      raw.required != 0, str(raw.default_value),
          raw.min_value, raw.max_value, str(raw.choices),  str(raw.doc)};
}

}  // namespace beslam::registry
