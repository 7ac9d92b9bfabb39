// Plugin configuration: schema entries (field::*, the raw form settings.hpp builds on) and the values the
// host validated against that schema and resolved (defaults filled) before create(). Plugins declare
// their settings with beslam::sdk::Settings (settings.hpp) and read them through it.
#pragma once

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "beslam/abi.h"

namespace beslam::sdk {

namespace field {
constexpr double kNoMin = 1.0, kNoMax = 0.0;  // min > max: unbounded
constexpr beslam_config_field Bool(const char* key, const char* def, const char* doc) {
  return {key, BESLAM_CONFIG_BOOL, def == nullptr, def, kNoMin, kNoMax, nullptr, doc};
}
constexpr beslam_config_field Int(const char* key, const char* def, double min, double max, const char* doc) {
  return {key, BESLAM_CONFIG_INT, def == nullptr, def, min, max, nullptr, doc};
}
constexpr beslam_config_field Double(const char* key, const char* def, double min, double max, const char* doc) {
  return {key, BESLAM_CONFIG_DOUBLE, def == nullptr, def, min, max, nullptr, doc};
}
// choices: "a|b|c" or nullptr for any string.
constexpr beslam_config_field String(const char* key, const char* def, const char* choices, const char* doc) {
  return {key, BESLAM_CONFIG_STRING, def == nullptr, def, kNoMin, kNoMax, choices, doc};
}
// A file or folder; relative values are resolved against the pipeline file's folder by the host.
constexpr beslam_config_field Path(const char* key, const char* def, const char* doc) {
  return {key, BESLAM_CONFIG_PATH, def == nullptr, def, kNoMin, kNoMax, nullptr, doc};
}
constexpr beslam_config_field DoubleList(const char* key, const char* def, double min, double max, const char* doc) {
  return {key, BESLAM_CONFIG_DOUBLE_LIST, def == nullptr, def, min, max, nullptr, doc};
}
}  // namespace field

// Thrown by a plugin for a configuration it cannot use; the SDK returns BESLAM_ERROR_INVALID_CONFIG.
class ConfigError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class Config {
 public:
  Config() = default;
  Config(const beslam_config_value* values, uint32_t count) : values_(values), count_(count) {}

  bool has(const char* key) const { return find(key) != nullptr; }
  uint32_t size() const { return count_; }
  const beslam_config_value& at(uint32_t i) const { return values_[i]; }
  const beslam_config_value* find(const char* key) const {
    for (uint32_t i = 0; i < count_; ++i)
      if (values_[i].key && std::strcmp(values_[i].key, key) == 0) return &values_[i];
    return nullptr;
  }
  bool getBool(const char* key) const { return get(key, BESLAM_CONFIG_BOOL).number != 0.0; }
  int64_t getInt(const char* key) const { return static_cast<int64_t>(get(key, BESLAM_CONFIG_INT).number); }
  double getDouble(const char* key) const { return get(key, BESLAM_CONFIG_DOUBLE).number; }
  std::string getString(const char* key) const {
    const beslam_config_value* v = find(key);
    if (v == nullptr || (v->type != BESLAM_CONFIG_STRING && v->type != BESLAM_CONFIG_PATH))
      throw ConfigError(std::string("configuration key '") + key + "' is missing or not a string");
    return v->text ? v->text : "";
  }
  std::vector<double> getList(const char* key) const {
    const beslam_config_value& v = get(key, BESLAM_CONFIG_DOUBLE_LIST);
    return std::vector<double>(v.list, v.list + v.list_size);
  }

 private:
  const beslam_config_value& get(const char* key, int32_t type) const {
    const beslam_config_value* v = find(key);
    if (v == nullptr) throw ConfigError(std::string("configuration key '") + key + "' is missing");
    if (v->type != type) throw ConfigError(std::string("configuration key '") + key + "' has another type");
    return *v;
  }
  const beslam_config_value* values_ = nullptr;
  uint32_t count_ = 0;
};

}  // namespace beslam::sdk
