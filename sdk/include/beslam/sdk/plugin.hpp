// The SDK core: what every plugin instance gets (Context, Frame), the descriptor and the export macro.
//
//   class MyDetector : public beslam::sdk::Detector { ... };            // see detector.hpp etc.
//   const beslam::sdk::Settings<Options> kSettings{...};                // see settings.hpp
//   BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MyDetector>({"my_detector", "My detector", "One line.",
//                                                            {1, 0, 0}, kSettings}))
//
// A plugin class is constructed as Impl(const beslam::sdk::Context&, const beslam::sdk::Config&); the
// Config is borrowed for the constructor only, the Context lives as long as the instance. Any exception
// a plugin throws becomes a status at the C boundary (ConfigError: INVALID_CONFIG, invalid_argument:
// INVALID_ARGUMENT, others: RUNTIME) with its message logged. The glue is in detail/plugin.hpp.
#pragma once

#include <cstdio>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <vector>

#include "beslam/plugin.h"
#include "beslam/sdk/config.hpp"
#include "beslam/sdk/settings.hpp"
#include "beslam/sdk/views.hpp"

namespace beslam::sdk {

// What an instance knows about its run: camera, LiDAR extrinsics, output folder, and a logger.
class Context {
 public:
  Context(const beslam_create_info& info, const char* plugin_id) : plugin_id_(plugin_id) {
    beslam_create_info local{};
    std::memcpy(&local, &info, std::min<size_t>(info.struct_size, sizeof(local)));
    host_ = local.host;
    camera_ = local.camera;
    if (local.has_lidar_extrinsics) T_cam_lidar_ = toIsometry(local.T_cam_lidar);
    output_dir_ = local.output_dir ? local.output_dir : "";
    if (local.camera_height > 0) camera_height_ = local.camera_height;  // ABI 1.1; 0 from older hosts
  }

  const beslam_camera& camera() const { return camera_; }
  const std::optional<Eigen::Isometry3d>& T_cam_lidar() const { return T_cam_lidar_; }
  const std::string& outputDir() const { return output_dir_; }
  // The rig: the camera centre's height over the road in metres, when the dataset (or pipeline) knows it.
  const std::optional<double>& cameraHeight() const { return camera_height_; }
  const std::string& pluginId() const { return plugin_id_; }

  void log(int32_t level, const std::string& message) const {
    if (host_ && host_->log) host_->log(host_->user_data, level, plugin_id_.c_str(), message.c_str());
  }
  void info(const std::string& message) const { log(BESLAM_LOG_INFO, message); }
  void warn(const std::string& message) const { log(BESLAM_LOG_WARNING, message); }

 private:
  const beslam_host* host_ = nullptr;
  std::string plugin_id_;
  beslam_camera camera_{};
  std::optional<Eigen::Isometry3d> T_cam_lidar_;
  std::string output_dir_;
  std::optional<double> camera_height_;
};

// One input frame as OpenCV/Eigen views over the host's memory (borrowed for the call).
struct Frame {
  int64_t index = 0;
  double timestamp = 0;
  cv::Mat gray;   // CV_8UC1
  cv::Mat color;  // CV_8UC3 BGR, may be empty
  beslam_point_cloud_view lidar{};
  std::string image_path;

  bool hasLidar() const { return lidar.data != nullptr && lidar.count > 0; }
  PointMap lidarPoints() const { return toEigen(lidar); }  // 4 x N: x y z intensity, LiDAR frame
};

struct Version {
  uint32_t major, minor, patch;
};

struct PluginInfo {
  const char* id;
  const char* name;
  const char* description;
  Version version;
  const beslam_config_field* fields = nullptr;
  uint32_t field_count = 0;

  template <size_t N>
  PluginInfo(const char* id_, const char* name_, const char* description_, Version version_,
             const beslam_config_field (&fields_)[N])
      : id(id_),
        name(name_),
        description(description_),
        version(version_),
        fields(fields_),
        field_count(static_cast<uint32_t>(N)) {}
  template <class O>
  PluginInfo(const char* id_, const char* name_, const char* description_, Version version_,
             const Settings<O>& settings)
      : id(id_),
        name(name_),
        description(description_),
        version(version_),
        fields(settings.fields()),
        field_count(settings.size()) {}
  PluginInfo(const char* id_, const char* name_, const char* description_, Version version_)
      : id(id_), name(name_), description(description_), version(version_) {}
};

// The descriptor of plugin class Impl (one per class, built on first use, valid while loaded).
// Impl derives from one kind base (Detector, MotionChecker, ...), which supplies kKind and its table.
template <class Impl>
const beslam_plugin_descriptor* describe(const PluginInfo& info);

}  // namespace beslam::sdk

#include "beslam/sdk/detail/plugin.hpp"

// Exports a library's plugins: BESLAM_EXPORT_PLUGINS(describe<A>({...}), describe<B>({...}))
#define BESLAM_EXPORT_PLUGINS(...)                                                                                   \
  extern "C" BESLAM_EXPORT uint32_t beslam_plugin_abi_version(void) { return BESLAM_ABI_VERSION; }                   \
  extern "C" BESLAM_EXPORT beslam_status beslam_plugin_list(const beslam_plugin_descriptor* const** out_descriptors, \
                                                            uint32_t* out_count) {                                   \
    if (out_descriptors == nullptr || out_count == nullptr) return BESLAM_ERROR_INVALID_ARGUMENT;                    \
    try {                                                                                                            \
      static const beslam_plugin_descriptor* const list[] = {__VA_ARGS__};                                           \
      *out_descriptors = list;                                                                                       \
      *out_count = static_cast<uint32_t>(sizeof(list) / sizeof(list[0]));                                            \
      return BESLAM_OK;                                                                                              \
    } catch (...) {                                                                                                  \
      return BESLAM_ERROR_INTERNAL;                                                                                  \
    }                                                                                                                \
  }
