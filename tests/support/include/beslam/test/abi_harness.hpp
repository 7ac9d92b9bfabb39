// Loads one plugin library with dlopen and drives it through the C ABI the way the host does: every
// schema key is filled from its default (then overridden), errors logged by the plugin are captured.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "beslam/plugin.h"

namespace beslam::test {

class AbiHarness {
 public:
  AbiHarness(const std::string& library, const std::string& plugin_id);  // throws std::runtime_error
  ~AbiHarness();
  AbiHarness(const AbiHarness&) = delete;
  AbiHarness& operator=(const AbiHarness&) = delete;

  const beslam_plugin_descriptor& descriptor() const { return *descriptor_; }

  // Creates an instance with the defaults plus `overrides` (YAML-ish text: numbers, true/false, strings,
  // "[a, b]" lists). Returns the status; on OK the instance is kept for detect().
  beslam_status create(const std::map<std::string, std::string>& overrides, const beslam_create_info& base);
  beslam_status detect(const beslam_frame& frame, beslam_box_list* out);

  const std::string& lastError() const { return last_error_; }
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  static void log(void* user, int32_t level, const char* id, const char* message);
  void destroyInstance();
  void* library_ = nullptr;
  const beslam_plugin_descriptor* descriptor_ = nullptr;
  void* instance_ = nullptr;
  beslam_host host_{};
  std::vector<std::string> texts_;  // owns config strings
  std::vector<std::vector<double>> lists_;
  std::vector<beslam_config_value> values_;
  std::string last_error_;
  std::vector<std::string> warnings_;
};

}  // namespace beslam::test
