#include "beslam/registry/instance.hpp"

#include <cmath>
#include <cstddef>
#include <cstring>
#include <iostream>

#include "beslam/common/error.hpp"
#include "beslam/formats/geometry.hpp"

namespace beslam::registry {

HostLog::HostLog(int32_t min_level) : min_level_(min_level) {
  host_.struct_size = sizeof(host_);
  host_.abi_version = BESLAM_ABI_VERSION;
  host_.user_data = this;
  host_.log = &HostLog::logCallback;
}

void HostLog::logCallback(void* user_data, int32_t level, const char* plugin_id, const char* message) {
  auto* self = static_cast<HostLog*>(user_data);
  const std::string id = plugin_id ? plugin_id : "?";
  const std::string text = message ? message : "";
  std::lock_guard<std::mutex> lock(self->mutex_);
  if (level >= BESLAM_LOG_ERROR) {
    for (auto& [pid, last] : self->last_error_)
      if (pid == id) {
        last = text;
        return;
      }
    self->last_error_.emplace_back(id, text);
    return;  // errors reach the user once, through the exception the host raises
  }
  if (level < self->min_level_) return;
  static const char* names[] = {"debug", "info", "warning", "error"};
  std::cerr << "[" << id << "] " << names[level < 0 ? 0 : (level > 3 ? 3 : level)] << ": " << text << "\n";
}

std::string HostLog::takeLastError(const std::string& plugin_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = last_error_.begin(); it != last_error_.end(); ++it)
    if (it->first == plugin_id) {
      std::string message = it->second;
      last_error_.erase(it);
      return message;
    }
  return {};
}

Instance::Instance(const Plugin& plugin, const beslam_create_info& info, HostLog& log) : plugin_(plugin), log_(log) {
  void* handle = nullptr;
  const beslam_status status = plugin.descriptor.create(&info, &handle);
  check(status, "create");
  if (handle == nullptr)
    throw Error("plugin " + plugin.id + " (" + plugin.library_path + "): create returned no instance");
  handle_ = handle;
}

Instance::~Instance() {
  if (handle_) plugin_.descriptor.destroy(handle_);
}

void Instance::check(beslam_status status, const char* call) const {
  if (status == BESLAM_OK) return;
  std::string message = log_.takeLastError(plugin_.id);
  throw Error("plugin " + plugin_.id + " (" + plugin_.library_path + "): " + call + " failed (" + statusName(status) +
              ")" + (message.empty() ? "" : ": " + message));
}

template <class Table>
Table Instance::table() const {
  Table t{};
  std::memcpy(&t, plugin_.functions, std::min<size_t>(plugin_.functions_size, sizeof(Table)));
  return t;
}

std::vector<beslam_box3d> DetectorInstance::detect(const beslam_frame& frame) {
  beslam_box_list out{};
  check(table<beslam_detector_v1>().detect(handle_, &frame, &out), "detect");
  if (out.count > 0 && (out.boxes == nullptr || out.element_size == 0))
    throw Error("plugin " + plugin().id + ": detect returned " + std::to_string(out.count) + " boxes without data");
  std::vector<beslam_box3d> boxes(out.count);
  const char* base = reinterpret_cast<const char*>(out.boxes);
  for (uint32_t i = 0; i < out.count; ++i)
    std::memcpy(&boxes[i], base + static_cast<size_t>(i) * out.element_size,
                std::min<size_t>(out.element_size, sizeof(beslam_box3d)));
  return boxes;
}

void MotionCheckerInstance::classify(const beslam_frame& frame, const std::optional<Eigen::Isometry3d>& T_world_cam,
                                     std::vector<beslam_box3d>& boxes) {
  beslam_pose pose{};
  if (T_world_cam)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) pose.m[r * 4 + c] = T_world_cam->matrix()(r, c);
  beslam_box_array array{boxes.data(), static_cast<uint32_t>(boxes.size()), sizeof(beslam_box3d)};
  check(table<beslam_motion_checker_v1>().classify(handle_, &frame, T_world_cam ? &pose : nullptr, &array), "classify");
}

void MotionCheckerInstance::worldMoved(const Eigen::Isometry3d& S_new_old, double scale) {
  const auto world_moved = table<beslam_motion_checker_v1>().world_moved;
  if (world_moved == nullptr) return;  // an ABI 1.6 checker
  const beslam_pose pose = formats::toPose(S_new_old);
  check(world_moved(handle_, &pose, scale), "world_moved");
}

void MaskGeneratorInstance::generate(const beslam_frame& frame, const std::vector<beslam_box3d>& boxes,
                                     beslam_mask_buffer& mask) {
  beslam_box_list list{boxes.data(), static_cast<uint32_t>(boxes.size()), sizeof(beslam_box3d)};
  check(table<beslam_mask_generator_v1>().generate(handle_, &frame, &list, &mask), "generate");
}

namespace {
using formats::toIsometry;

// Copies the plugin's landmarks (plugin memory, element_size as the plugin was built) into host memory.
Landmarks copyLandmarks(const beslam_landmark_list& out, const std::string& plugin) {
  try {
    return sdk::fromC(&out);
  } catch (const std::invalid_argument& e) {
    throw Error("plugin " + plugin + ": returned " + e.what());
  }
}
}  // namespace

Landmarks ReconstructorInstance::reconstruct(const beslam_keyframe& keyframe, const beslam_frame& frame,
                                             const std::vector<beslam_box3d>& boxes, const beslam_image_view& mask) {
  beslam_box_list list{boxes.data(), static_cast<uint32_t>(boxes.size()), sizeof(beslam_box3d)};
  beslam_landmark_list out{};
  check(table<beslam_reconstructor_v1>().reconstruct(handle_, &keyframe, &frame, &list, &mask, &out), "reconstruct");
  return copyLandmarks(out, plugin().id);
}

Landmarks ReconstructorInstance::finish() {
  const auto finish = table<beslam_reconstructor_v1>().finish;
  if (finish == nullptr) return {};  // an ABI 1.2 plugin
  beslam_landmark_list out{};
  check(finish(handle_, &out), "finish");
  return copyLandmarks(out, plugin().id);
}

std::optional<Eigen::Isometry3d> BackendInstance::predictPose(const beslam_frame& frame) {
  beslam_pose pose{};
  int32_t valid = 0;
  check(table<beslam_backend_v1>().predict_pose(handle_, &frame, &pose, &valid), "predict_pose");
  if (!valid) return std::nullopt;
  return toIsometry(pose);
}

bool BackendInstance::hasPrepare() const { return table<beslam_backend_v1>().prepare != nullptr; }

void BackendInstance::prepare(const beslam_frame& frame) {
  const auto prepare = table<beslam_backend_v1>().prepare;
  if (prepare != nullptr) check(prepare(handle_, &frame), "prepare");
}

TrackOutput BackendInstance::track(const beslam_frame& frame, const beslam_image_view& mask,
                                   const std::vector<beslam_box3d>& boxes) {
  beslam_box_list list{boxes.data(), static_cast<uint32_t>(boxes.size()), sizeof(beslam_box3d)};
  TrackOutput out;
  out.result.struct_size = sizeof(beslam_track_result);
  check(table<beslam_backend_v1>().track(handle_, &frame, &mask, &list, &out.result), "track");
  for (uint32_t i = 0; i < out.result.stage_count && out.result.stage_times; ++i)
    out.stage_ms.emplace_back(out.result.stage_times[i].name ? out.result.stage_times[i].name : "?",
                              out.result.stage_times[i].milliseconds);
  for (uint32_t i = 0; i < out.result.counter_count && out.result.counters; ++i)
    out.counters.emplace_back(out.result.counters[i].name ? out.result.counters[i].name : "?",
                              out.result.counters[i].value);
  if (out.result.keypoints && out.result.keypoint_size >= sizeof(beslam_keypoint)) {
    const auto* bytes = reinterpret_cast<const uint8_t*>(out.result.keypoints);
    out.keypoints.resize(out.result.keypoint_count);
    for (uint32_t i = 0; i < out.result.keypoint_count; ++i)
      std::memcpy(&out.keypoints[i], bytes + size_t(i) * out.result.keypoint_size, sizeof(beslam_keypoint));
  }
  if (out.result.keyframe_points && out.result.keyframe_point_size >= sizeof(beslam_keyframe_point)) {
    const auto* bytes = reinterpret_cast<const uint8_t*>(out.result.keyframe_points);
    out.keyframe_points.resize(out.result.keyframe_point_count);
    for (uint32_t i = 0; i < out.result.keyframe_point_count; ++i)
      std::memcpy(&out.keyframe_points[i], bytes + size_t(i) * out.result.keyframe_point_size,
                  sizeof(beslam_keyframe_point));
  }
  if (out.result.world_moved != 0) {
    bool finite = std::isfinite(out.result.world_change_scale) && out.result.world_change_scale > 0;
    for (double v : out.result.S_new_old.m) finite = finite && std::isfinite(v);
    if (!finite)
      throw Error("plugin " + plugin().id + ": track moved the world by a non-finite change or a scale <= 0");
  }
  out.result.keypoints = nullptr;
  out.result.keypoint_count = 0;
  out.result.keyframe_points = nullptr;
  out.result.keyframe_point_count = 0;
  out.result.stage_times = nullptr;  // plugin memory: not to be kept
  out.result.stage_count = 0;
  out.result.counters = nullptr;
  out.result.counter_count = 0;
  return out;
}

std::optional<TrackOutput::WorldChange> TrackOutput::worldChange() const {
  if (result.world_moved == 0) return std::nullopt;
  return WorldChange{formats::toIsometry(result.S_new_old), result.world_change_scale};
}

void BackendInstance::addLandmarks(const Landmarks& landmarks) {
  std::vector<beslam_object_landmark> views = sdk::toC(landmarks);  // views of the host's copies, for this call
  beslam_landmark_list list{views.data(), static_cast<uint32_t>(views.size()), sizeof(beslam_object_landmark)};
  check(table<beslam_backend_v1>().add_landmarks(handle_, &list), "add_landmarks");
}

void BackendInstance::finish() { check(table<beslam_backend_v1>().finish(handle_), "finish"); }

std::vector<PoseEntry> BackendInstance::trajectory(int32_t which) {
  beslam_trajectory_list list{};
  check(table<beslam_backend_v1>().trajectory(handle_, which, &list), "trajectory");
  std::vector<PoseEntry> out;
  const char* base = reinterpret_cast<const char*>(list.entries);
  for (uint32_t i = 0; i < list.count; ++i) {
    beslam_trajectory_entry e{};
    std::memcpy(&e, base + static_cast<size_t>(i) * list.element_size, std::min<size_t>(list.element_size, sizeof(e)));
    out.push_back({e.frame_index, e.timestamp, toIsometry(e.T_world_cam)});
  }
  return out;
}

std::vector<beslam_map_point> BackendInstance::mapPoints() {
  beslam_map_point_list list{};
  check(table<beslam_backend_v1>().map_points(handle_, &list), "map_points");
  std::vector<beslam_map_point> out(list.count);
  const char* base = reinterpret_cast<const char*>(list.points);
  for (uint64_t i = 0; i < list.count; ++i)
    std::memcpy(&out[i], base + i * list.element_size, std::min<size_t>(list.element_size, sizeof(beslam_map_point)));
  return out;
}

}  // namespace beslam::registry
