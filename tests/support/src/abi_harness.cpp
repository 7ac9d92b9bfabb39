#include "beslam/test/abi_harness.hpp"

#include <dlfcn.h>

#include <cstring>
#include <sstream>
#include <stdexcept>

namespace beslam::test {

namespace {
std::string trimQuotes(std::string s) {
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}
std::vector<double> parseList(std::string s) {
  for (char& c : s)
    if (c == '[' || c == ']' || c == ',') c = ' ';
  std::istringstream in(s);
  std::vector<double> out;
  for (double v; in >> v;) out.push_back(v);
  return out;
}
}  // namespace

AbiHarness::AbiHarness(const std::string& library, const std::string& plugin_id) {
  library_ = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (library_ == nullptr) throw std::runtime_error("dlopen " + library + ": " + dlerror());
  auto list = reinterpret_cast<beslam_plugin_list_fn>(dlsym(library_, BESLAM_PLUGIN_LIST_SYMBOL));
  if (list == nullptr) throw std::runtime_error(library + ": no " BESLAM_PLUGIN_LIST_SYMBOL);
  const beslam_plugin_descriptor* const* descriptors = nullptr;
  uint32_t count = 0;
  if (list(&descriptors, &count) != BESLAM_OK) throw std::runtime_error(library + ": plugin list failed");
  for (uint32_t i = 0; i < count; ++i)
    if (plugin_id == descriptors[i]->id) descriptor_ = descriptors[i];
  if (descriptor_ == nullptr) throw std::runtime_error(library + ": no plugin " + plugin_id);
  host_.struct_size = sizeof(host_);
  host_.abi_version = BESLAM_ABI_VERSION;
  host_.user_data = this;
  host_.log = &AbiHarness::log;
}

AbiHarness::~AbiHarness() {
  destroyInstance();
  // The library stays loaded: static state of a module may still be referenced at exit.
}

void AbiHarness::destroyInstance() {
  if (instance_ != nullptr) descriptor_->destroy(instance_);
  instance_ = nullptr;
}

void AbiHarness::log(void* user, int32_t level, const char*, const char* message) {
  auto* self = static_cast<AbiHarness*>(user);
  if (level >= BESLAM_LOG_ERROR)
    self->last_error_ = message;
  else if (level == BESLAM_LOG_WARNING)
    self->warnings_.push_back(message);
}

beslam_status AbiHarness::create(const std::map<std::string, std::string>& overrides, const beslam_create_info& base) {
  destroyInstance();
  texts_.clear(), lists_.clear(), values_.clear(), last_error_.clear();
  const uint32_t n = descriptor_->config_field_count;
  texts_.reserve(n), lists_.reserve(n);
  for (uint32_t i = 0; i < n; ++i) {
    const beslam_config_field& f = descriptor_->config_fields[i];
    auto it = overrides.find(f.key);
    const std::string text = it != overrides.end() ? it->second : (f.default_value ? f.default_value : "");
    beslam_config_value v{};
    v.key = f.key;
    v.type = f.type;
    texts_.push_back(trimQuotes(text));
    lists_.push_back({});
    switch (f.type) {
      case BESLAM_CONFIG_BOOL:
        v.number = text == "true" ? 1 : 0;
        break;
      case BESLAM_CONFIG_INT:
      case BESLAM_CONFIG_DOUBLE:
        v.number = std::stod(text);
        break;
      case BESLAM_CONFIG_DOUBLE_LIST:
        lists_.back() = parseList(text);
        break;
      default:
        break;
    }
    v.text = texts_.back().c_str();
    v.list = lists_.back().data();
    v.list_size = lists_.back().size();
    values_.push_back(v);
  }
  beslam_create_info info = base;
  info.struct_size = sizeof(info);
  info.host = &host_;
  info.config = values_.data();
  info.config_count = static_cast<uint32_t>(values_.size());
  return descriptor_->create(&info, &instance_);
}

beslam_status AbiHarness::detect(const beslam_frame& frame, beslam_box_list* out) {
  if (instance_ == nullptr) throw std::runtime_error("detect before a successful create");
  last_error_.clear();
  const auto* table = static_cast<const beslam_detector_v1*>(descriptor_->functions);
  return table->detect(instance_, &frame, out);
}

}  // namespace beslam::test
