// The backend_orb plugin the way the host uses it: dlopen, the C descriptor, create from schema
// defaults, track rendered frames through the C function table, read the trajectory, destroy; save a map
// in finish, localise in it in another instance, and a map file that cannot be loaded is the creation's
// error text.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "beslam/abi.h"
#include "beslam/data.h"
#include "beslam/kinds/backend.h"
#include "synthetic_world.hpp"

namespace {

struct Loaded {
  void* handle = nullptr;
  const beslam_plugin_descriptor* desc = nullptr;
  ~Loaded() {
    if (handle) dlclose(handle);
  }
};

void load(Loaded& l) {
  const std::string path = std::string(PLUGIN_DIR) + "/backend_orb.so";
  l.handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(l.handle, nullptr) << dlerror();
  auto list = reinterpret_cast<beslam_status (*)(const beslam_plugin_descriptor* const**, uint32_t*)>(
      dlsym(l.handle, BESLAM_PLUGIN_LIST_SYMBOL));
  ASSERT_NE(list, nullptr);
  const beslam_plugin_descriptor* const* descs = nullptr;
  uint32_t n = 0;
  ASSERT_EQ(list(&descs, &n), BESLAM_OK);
  for (uint32_t i = 0; i < n; ++i)
    if (std::strcmp(descs[i]->id, "backend_orb") == 0) l.desc = descs[i];
  ASSERT_NE(l.desc, nullptr);
  EXPECT_EQ(l.desc->kind, BESLAM_KIND_BACKEND);
}

// Schema defaults as the host would fill them, with optional overrides.
std::vector<beslam_config_value> defaults(const beslam_plugin_descriptor* d, const char* key = nullptr,
                                          double value = 0) {
  std::vector<beslam_config_value> v;
  for (uint32_t i = 0; i < d->config_field_count; ++i) {
    const beslam_config_field& f = d->config_fields[i];
    beslam_config_value c{};
    c.key = f.key;
    c.type = f.type;
    const std::string def = f.default_value ? f.default_value : "";
    c.number = def == "true" ? 1.0 : def == "false" ? 0.0 : std::strtod(def.c_str(), nullptr);
    if (f.type == BESLAM_CONFIG_STRING && !def.empty() && def[0] != '"') c.text = f.default_value;  // a choice
    if (key && std::strcmp(key, f.key) == 0) c.number = value;
    v.push_back(c);
  }
  return v;
}

void setText(std::vector<beslam_config_value>& config, const char* key, const char* text) {
  for (beslam_config_value& c : config)
    if (std::strcmp(c.key, key) == 0) c.text = text;
}

void setNumber(std::vector<beslam_config_value>& config, const char* key, double value) {
  for (beslam_config_value& c : config)
    if (std::strcmp(c.key, key) == 0) c.number = value;
}

beslam_create_info createInfo(const std::vector<beslam_config_value>& config) {
  const beslam::orb::Camera cam = beslam::orb::test::CorridorWorld().camera();
  beslam_create_info info{};
  info.struct_size = sizeof(info);
  info.config = config.data();
  info.config_count = static_cast<uint32_t>(config.size());
  info.camera = {sizeof(beslam_camera), cam.width, cam.height, 0, cam.fx, cam.fy, cam.cx, cam.cy};
  return info;
}

// Renders corridor frame i (10 frames a second) and tracks it through the C table into `result`; returns
// the call's status.
int32_t trackFrame(const beslam_backend_v1* table, void* instance, const beslam::orb::test::CorridorWorld& world, int i,
                   beslam_track_result& result) {
  const cv::Mat image = world.render(i);
  beslam_frame frame{};
  frame.struct_size = sizeof(frame);
  frame.index = i;
  frame.timestamp = 0.1 * i;
  frame.gray = {image.data, image.cols, image.rows, static_cast<int32_t>(image.step), BESLAM_PIXEL_GRAY8};
  result = beslam_track_result{};
  result.struct_size = sizeof(result);
  return table->track(instance, &frame, nullptr, nullptr, &result);
}

TEST(BackendOrbPlugin, TracksThroughTheCAbi) {
  Loaded l;
  load(l);
  if (HasFatalFailure()) return;
  const auto config = defaults(l.desc, "features", 1000);
  const beslam_create_info info = createInfo(config);
  void* instance = nullptr;
  ASSERT_EQ(l.desc->create(&info, &instance), BESLAM_OK);
  const auto* table = static_cast<const beslam_backend_v1*>(l.desc->functions);
  const beslam::orb::test::CorridorWorld world;
  int ok_frames = 0;
  for (int i = 0; i < 15; ++i) {
    beslam_track_result result{};
    ASSERT_EQ(trackFrame(table, instance, world, i, result), BESLAM_OK);
    ok_frames += result.state == BESLAM_TRACKING_OK;
    EXPECT_GT(result.stage_count, 0u);
  }
  EXPECT_GE(ok_frames, 10);
  ASSERT_EQ(table->finish(instance), BESLAM_OK);
  beslam_trajectory_list traj{};
  ASSERT_EQ(table->trajectory(instance, BESLAM_TRAJECTORY_FINAL, &traj), BESLAM_OK);
  EXPECT_GE(traj.count, 10u);
  beslam_map_point_list points{};
  ASSERT_EQ(table->map_points(instance, &points), BESLAM_OK);
  EXPECT_GT(points.count, 100u);
  EXPECT_NE(table->trajectory(instance, 99, &traj), BESLAM_OK);
  l.desc->destroy(instance);
}

TEST(BackendOrbPlugin, RejectsAnInvalidConfiguration) {
  Loaded l;
  load(l);
  if (HasFatalFailure()) return;
  const auto config = defaults(l.desc, "fast_fallback", 50);  // above fast_initial (20)
  const beslam_create_info info = createInfo(config);
  void* instance = nullptr;
  EXPECT_EQ(l.desc->create(&info, &instance), BESLAM_ERROR_INVALID_CONFIG);
  EXPECT_EQ(instance, nullptr);
}

// Tracks `frames` rendered corridor frames through the C table; returns how many were tracked.
int trackFrames(const beslam_backend_v1* table, void* instance, int first, int frames) {
  const beslam::orb::test::CorridorWorld world;
  int ok_frames = 0;
  for (int i = first; i < first + frames; ++i) {
    beslam_track_result result{};
    if (trackFrame(table, instance, world, i, result) != BESLAM_OK) return -1;
    ok_frames += result.state == BESLAM_TRACKING_OK;
  }
  return ok_frames;
}

// An instance made from `config` tracks frames [first, first + frames) and finishes; how many were tracked
// (-1 when creating, tracking or finishing failed).
int trackAndFinish(const beslam_plugin_descriptor* desc, const std::vector<beslam_config_value>& config, int first,
                   int frames) {
  const beslam_create_info info = createInfo(config);
  void* instance = nullptr;
  if (desc->create(&info, &instance) != BESLAM_OK) return -1;
  const auto* table = static_cast<const beslam_backend_v1*>(desc->functions);
  int tracked = trackFrames(table, instance, first, frames);
  if (table->finish(instance) != BESLAM_OK) tracked = -1;
  desc->destroy(instance);
  return tracked;
}

void keepLastError(void* user_data, int32_t level, const char*, const char* message) {
  if (level == BESLAM_LOG_ERROR) *static_cast<std::string*>(user_data) = message;
}

TEST(BackendOrbPlugin, SavesAMapAndLocalisesInIt) {
  Loaded l;
  load(l);
  if (HasFatalFailure()) return;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("beslam_orb_plugin_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string map_file = (dir / "corridor.map").string();
  {
    auto config = defaults(l.desc, "features", 1000);
    setText(config, "save_map", map_file.c_str());
    EXPECT_GE(trackAndFinish(l.desc, config, 0, 15), 10);
  }
  ASSERT_TRUE(std::filesystem::exists(map_file));
  {
    auto config = defaults(l.desc, "features", 1000);
    setText(config, "load_map", map_file.c_str());
    setNumber(config, "localisation_only", 1);
    EXPECT_EQ(trackAndFinish(l.desc, config, 2, 10), 10);
  }
  {
    const auto size = std::filesystem::file_size(map_file);
    std::filesystem::resize_file(map_file, size / 2);
    auto config = defaults(l.desc, "features", 1000);
    setText(config, "load_map", map_file.c_str());
    beslam_create_info info = createInfo(config);
    std::string error;
    beslam_host host{sizeof(beslam_host), BESLAM_ABI_VERSION, &error, keepLastError};
    info.host = &host;
    void* instance = nullptr;
    EXPECT_EQ(l.desc->create(&info, &instance), BESLAM_ERROR_RUNTIME);
    EXPECT_EQ(instance, nullptr);
    EXPECT_NE(error.find("map file '" + map_file + "': truncated"), std::string::npos) << error;
  }
  {
    auto config = defaults(l.desc, "features", 1000);
    setNumber(config, "localisation_only", 1);  // without load_map
    const beslam_create_info info = createInfo(config);
    void* instance = nullptr;
    EXPECT_EQ(l.desc->create(&info, &instance), BESLAM_ERROR_INVALID_CONFIG);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
