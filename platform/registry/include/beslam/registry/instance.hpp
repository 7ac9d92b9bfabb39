// Host-side handles to plugin instances: create/destroy in RAII, typed calls per kind, and every non-OK
// status turned into a beslam::Error that names the plugin, its library, the call and the message the
// plugin logged. The host log sink prints plugin messages to stderr with the plugin id; it may be called
// from several threads at once (the runner calls plugins from a producer thread too).
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "beslam/plugin.h"
#include "beslam/registry/registry.hpp"
#include "beslam/sdk/landmark.hpp"

namespace beslam::registry {

// Where plugins' log messages go; also remembers the last ERROR each plugin logged.
class HostLog {
 public:
  explicit HostLog(int32_t min_level = BESLAM_LOG_INFO);
  const beslam_host* host() const { return &host_; }
  std::string takeLastError(const std::string& plugin_id);
  void setMinLevel(int32_t level) { min_level_ = level; }

 private:
  static void logCallback(void* user_data, int32_t level, const char* plugin_id, const char* message);
  beslam_host host_{};
  int32_t min_level_;
  std::mutex mutex_;                                             // guards last_error_ and the stderr lines
  std::vector<std::pair<std::string, std::string>> last_error_;  // plugin id -> message
};

class Instance {
 public:
  // Creates an instance; throws beslam::Error on a non-OK create or a null instance.
  Instance(const Plugin& plugin, const beslam_create_info& info, HostLog& log);
  ~Instance();
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;

  const Plugin& plugin() const { return plugin_; }

 protected:
  void check(beslam_status status, const char* call) const;
  template <class Table>
  Table table() const;  // the kind's table, zero-filled past what the plugin knows
  void* handle_ = nullptr;

 private:
  const Plugin& plugin_;
  HostLog& log_;
};

class DetectorInstance : public Instance {
 public:
  using Instance::Instance;
  std::vector<beslam_box3d> detect(const beslam_frame& frame);
};

class MotionCheckerInstance : public Instance {
 public:
  using Instance::Instance;
  void classify(const beslam_frame& frame, const std::optional<Eigen::Isometry3d>& T_world_cam,
                std::vector<beslam_box3d>& boxes);
  // ABI 1.7: the backend moved its world (p_new = scale * R * p_old + t, [R | t] = S_new_old); nothing for a
  // checker without the call (an older table, or NULL).
  void worldMoved(const Eigen::Isometry3d& S_new_old, double scale);
};

class MaskGeneratorInstance : public Instance {
 public:
  using Instance::Instance;
  void generate(const beslam_frame& frame, const std::vector<beslam_box3d>& boxes, beslam_mask_buffer& mask);
};

// One object a reconstructor returned, owned by the host (no pointer into plugin memory or into itself).
// A reconstructor's object landmark, owned by the host: the SDK's type, read through the SDK's checked copy
// (sdk::fromC) and handed on to a backend through its C view (sdk::toC).
using ObjectLandmark = sdk::Landmark;
using Landmarks = std::vector<ObjectLandmark>;

class ReconstructorInstance : public Instance {
 public:
  using Instance::Instance;
  Landmarks reconstruct(const beslam_keyframe& keyframe, const beslam_frame& frame,
                        const std::vector<beslam_box3d>& boxes, const beslam_image_view& mask);
  // ABI 1.3: the last updates of the run; empty from a reconstructor without finish().
  Landmarks finish();
};

struct TrackOutput {
  beslam_track_result result{};  // stage_times and counters cleared (plugin memory): read the copies below
  std::vector<std::pair<std::string, double>> stage_ms;
  std::vector<std::pair<std::string, double>> counters;
  std::vector<beslam_keypoint> keypoints;              // ABI 1.2 (empty from older backends)
  std::vector<beslam_keyframe_point> keyframe_points;  // ABI 1.3: what a new keyframe observes
  bool worldIsMetric() const { return result.world_scale == BESLAM_WORLD_SCALE_METRIC; }
  // ABI 1.7: how this call moved the backend's world (p_new = scale * R * p_old + t); nullopt when it did not.
  struct WorldChange {
    Eigen::Isometry3d S_new_old;
    double scale;
  };
  std::optional<WorldChange> worldChange() const;
};

struct PoseEntry {
  int64_t frame_index;
  double timestamp;
  Eigen::Isometry3d T_world_cam;
};

class BackendInstance : public Instance {
 public:
  using Instance::Instance;
  std::optional<Eigen::Isometry3d> predictPose(const beslam_frame& frame);
  TrackOutput track(const beslam_frame& frame, const beslam_image_view& mask, const std::vector<beslam_box3d>& boxes);
  void addLandmarks(const Landmarks& landmarks);
  void finish();
  std::vector<PoseEntry> trajectory(int32_t which);
  std::vector<beslam_map_point> mapPoints();
  // ABI 1.4: the frame's mask-independent work ahead of its track(), from the producer thread; nothing
  // for a backend without it (an older table, or NULL).
  void prepare(const beslam_frame& frame);
  bool hasPrepare() const;
};

}  // namespace beslam::registry
