// The SDK core: what every plugin instance gets (Context, Frame), the noexcept guard that turns C++
// exceptions into status codes, the descriptor builder and the one export macro.
//
//   class MyDetector : public beslam::sdk::Detector { ... };            // see detector.hpp etc.
//   static const beslam_config_field kFields[] = {beslam::sdk::field::Double("min_score", "0.3", 0, 1, "...")};
//   BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MyDetector>({"my_detector", "My detector", "One line.",
//                                                            {1, 0, 0}, kFields}))
//
// A plugin class is constructed as Impl(const beslam::sdk::Context&, const beslam::sdk::Config&); the
// Config is borrowed for the constructor only, the Context lives as long as the instance.
#pragma once

#include <cstdio>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <vector>

#include "beslam/plugin.h"
#include "beslam/sdk/config.hpp"
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

inline Frame toFrame(const beslam_frame* frame) {
  if (frame == nullptr) throw std::invalid_argument("frame is null");
  beslam_frame f{};
  std::memcpy(&f, frame, std::min<size_t>(frame->struct_size, sizeof(f)));
  Frame out;
  out.index = f.index;
  out.timestamp = f.timestamp;
  out.gray = toMat(f.gray);
  out.color = toMat(f.color);
  out.lidar = f.lidar;
  out.image_path = f.image_path ? f.image_path : "";
  return out;
}

namespace detail {

// Runs f, mapping every exception to a status and logging its message: nothing crosses the C ABI.
template <class F>
beslam_status guarded(const Context* context, F&& f) noexcept {
  auto report = [context](const char* what) noexcept {
    try {
      if (context) context->log(BESLAM_LOG_ERROR, what);
    } catch (...) {
    }
  };
  try {
    f();
    return BESLAM_OK;
  } catch (const ConfigError& e) {
    report(e.what());
    return BESLAM_ERROR_INVALID_CONFIG;
  } catch (const std::bad_alloc&) {
    report("out of memory");
    return BESLAM_ERROR_OUT_OF_MEMORY;
  } catch (const std::invalid_argument& e) {
    report(e.what());
    return BESLAM_ERROR_INVALID_ARGUMENT;
  } catch (const std::exception& e) {
    report(e.what());
    return BESLAM_ERROR_RUNTIME;
  } catch (...) {
    report("unknown exception");
    return BESLAM_ERROR_INTERNAL;
  }
}

// An instance as the host sees it: the context outlives the plugin object built from it.
template <class Impl>
struct Instance {
  explicit Instance(const beslam_create_info& info, const char* id) : context(info, id) {}
  Context context;
  std::unique_ptr<Impl> impl;
};

template <class Impl>
Instance<Impl>* cast(void* instance) {
  if (instance == nullptr) throw std::invalid_argument("instance is null");
  return static_cast<Instance<Impl>*>(instance);
}

}  // namespace detail

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
      : id(id_), name(name_), description(description_), version(version_), fields(fields_),
        field_count(static_cast<uint32_t>(N)) {}
  PluginInfo(const char* id_, const char* name_, const char* description_, Version version_)
      : id(id_), name(name_), description(description_), version(version_) {}
};

// The descriptor of plugin class Impl (one per class, built on first use, valid while loaded).
// Impl derives from one kind base (Detector, MotionChecker, ...), which supplies kKind and its table.
template <class Impl>
const beslam_plugin_descriptor* describe(const PluginInfo& info) {
  static const std::string id = info.id;
  static beslam_plugin_descriptor d = [&info] {
    beslam_plugin_descriptor desc{};
    desc.struct_size = sizeof(beslam_plugin_descriptor);
    desc.abi_version = BESLAM_ABI_VERSION;
    desc.id = id.c_str();
    desc.name = info.name;
    desc.description = info.description;
    desc.kind = Impl::kKind;
    desc.version_major = info.version.major;
    desc.version_minor = info.version.minor;
    desc.version_patch = info.version.patch;
    desc.config_fields = info.fields;
    desc.config_field_count = info.field_count;
    desc.config_field_size = sizeof(beslam_config_field);
    desc.create = [](const beslam_create_info* create_info, void** out) -> beslam_status {
      if (create_info == nullptr || out == nullptr) return BESLAM_ERROR_INVALID_ARGUMENT;
      *out = nullptr;
      detail::Instance<Impl>* instance = nullptr;
      try {
        instance = new detail::Instance<Impl>(*create_info, id.c_str());
      } catch (...) {
        return BESLAM_ERROR_OUT_OF_MEMORY;
      }
      const Config config(create_info->config, create_info->config_count);
      const beslam_status status = detail::guarded(&instance->context, [&] {
        instance->impl = std::make_unique<Impl>(instance->context, config);
      });
      if (status != BESLAM_OK) {
        delete instance;
        return status;
      }
      *out = instance;
      return BESLAM_OK;
    };
    desc.destroy = [](void* instance) {
      try {
        delete static_cast<detail::Instance<Impl>*>(instance);
      } catch (...) {
      }
    };
    desc.functions = Impl::template functionTable<Impl>();
    return desc;
  }();
  return &d;
}

}  // namespace beslam::sdk

// Exports a library's plugins: BESLAM_EXPORT_PLUGINS(describe<A>({...}), describe<B>({...}))
#define BESLAM_EXPORT_PLUGINS(...)                                                                     \
  extern "C" BESLAM_EXPORT uint32_t beslam_plugin_abi_version(void) { return BESLAM_ABI_VERSION; }   \
  extern "C" BESLAM_EXPORT beslam_status beslam_plugin_list(                                          \
      const beslam_plugin_descriptor* const** out_descriptors, uint32_t* out_count) {                 \
    if (out_descriptors == nullptr || out_count == nullptr) return BESLAM_ERROR_INVALID_ARGUMENT;      \
    try {                                                                                              \
      static const beslam_plugin_descriptor* const list[] = {__VA_ARGS__};                            \
      *out_descriptors = list;                                                                         \
      *out_count = static_cast<uint32_t>(sizeof(list) / sizeof(list[0]));                             \
      return BESLAM_OK;                                                                                \
    } catch (...) {                                                                                    \
      return BESLAM_ERROR_INTERNAL;                                                                    \
    }                                                                                                  \
  }
