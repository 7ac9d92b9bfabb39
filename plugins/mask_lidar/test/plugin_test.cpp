// mask_box and mask_lidar through the C ABI, as the host loads them: descriptors, configuration errors,
// labels written into the host's buffer, LiDAR-less frames.
#include "beslam/plugin.h"

#include <dlfcn.h>
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <string>

#include "beslam/sdk/views.hpp"

namespace {

struct Library {
  void* handle = nullptr;
  const beslam_plugin_descriptor* d = nullptr;
  explicit Library(const std::string& id) {
    const std::string path = std::string(BESLAM_BINARY_DIR) + "/lib/beslam/plugins/" + id + ".so";
    handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) return;
    auto list = reinterpret_cast<beslam_plugin_list_fn>(dlsym(handle, BESLAM_PLUGIN_LIST_SYMBOL));
    const beslam_plugin_descriptor* const* ds = nullptr;
    uint32_t n = 0;
    if (list && list(&ds, &n) == BESLAM_OK && n == 1) d = ds[0];
  }
  ~Library() {
    if (handle) dlclose(handle);
  }
};

std::string last_error;
void logSink(void*, int32_t level, const char*, const char* message) {
  if (level == BESLAM_LOG_ERROR) last_error = message;
}

// Every schema key with its default, overridden by `set` (numbers and strings as text).
struct Config {
  std::vector<std::string> texts;
  std::vector<beslam_config_value> values;
  Config(const beslam_plugin_descriptor* d, const std::map<std::string, std::string>& set) {
    texts.reserve(d->config_field_count);
    for (uint32_t i = 0; i < d->config_field_count; ++i) {
      const beslam_config_field& f = d->config_fields[i];
      const auto it = set.find(f.key);
      texts.push_back(it != set.end() ? it->second : (f.default_value ? f.default_value : ""));
    }
    for (uint32_t i = 0; i < d->config_field_count; ++i) {
      const beslam_config_field& f = d->config_fields[i];
      beslam_config_value v{};
      v.key = f.key;
      v.type = f.type;
      const std::string& t = texts[i];
      if (f.type == BESLAM_CONFIG_BOOL)
        v.number = t == "true" ? 1 : 0;
      else if (f.type == BESLAM_CONFIG_INT || f.type == BESLAM_CONFIG_DOUBLE)
        v.number = std::stod(t);
      else
        v.text = t.c_str();
      values.push_back(v);
    }
  }
};

beslam_create_info info(const Config& c, const beslam_host* host, bool extrinsics) {
  beslam_create_info i{};
  i.struct_size = sizeof(i);
  i.host = host;
  i.config = c.values.data();
  i.config_count = static_cast<uint32_t>(c.values.size());
  i.camera = {sizeof(beslam_camera), 1200, 360, 0, 700, 700, 600, 180};
  if (extrinsics) {
    i.has_lidar_extrinsics = 1;
    i.T_cam_lidar = {{0, -1, 0, 0, 0, 0, -1, -0.08, 1, 0, 0, -0.27}};
  }
  i.output_dir = "";
  return i;
}

beslam_box3d box(int id, int motion, double x) {
  beslam_box3d b{};
  b.class_id = BESLAM_CLASS_CAR;
  b.track_id = id;
  b.motion_state = motion;
  b.center_cam[0] = x, b.center_cam[1] = 0.9, b.center_cam[2] = 12;
  b.size[0] = 4, b.size[1] = 1.8, b.size[2] = 1.5;
  b.yaw = M_PI / 2;
  return b;
}

}  // namespace

TEST(Plugins, WriteLabelsThroughTheAbi) {
  const beslam_host host{sizeof(beslam_host), BESLAM_ABI_VERSION, nullptr, logSink};
  for (const char* id : {"mask_box", "mask_lidar"}) {
    Library lib(id);
    ASSERT_NE(lib.d, nullptr) << id << ": " << dlerror();
    EXPECT_STREQ(lib.d->id, id);
    EXPECT_EQ(lib.d->kind, BESLAM_KIND_MASK_GENERATOR);
    const Config config(lib.d, {});
    const beslam_create_info ci = info(config, &host, true);
    void* inst = nullptr;
    ASSERT_EQ(lib.d->create(&ci, &inst), BESLAM_OK) << id << ": " << last_error;
    const auto* table = static_cast<const beslam_mask_generator_v1*>(lib.d->functions);
    std::vector<uint8_t> gray(1200 * 360, 100);
    beslam_frame frame{};
    frame.struct_size = sizeof(frame);
    frame.gray = {gray.data(), 1200, 360, 1200, BESLAM_PIXEL_GRAY8};
    const beslam_box3d boxes[] = {box(5, BESLAM_MOTION_STATIC, -3), box(6, BESLAM_MOTION_DYNAMIC, 3),
                                  box(7, BESLAM_MOTION_UNKNOWN, 0)};
    const beslam_box_list list{boxes, 3, sizeof(beslam_box3d)};
    std::vector<uint16_t> mask(1200 * 360, 0);
    beslam_mask_buffer buf{mask.data(), 1200, 360, 2400, 0};
    // No scan in the frame: mask_lidar falls back to box projection.
    ASSERT_EQ(table->generate(inst, &frame, &list, &buf), BESLAM_OK) << id << ": " << last_error;
    auto at = [&](double x) {
      const int u = static_cast<int>(600 + 700 * x / 12), v = static_cast<int>(180 + 700 * 0.9 / 12);
      return mask[v * 1200 + u];
    };
    EXPECT_EQ(at(-3), 1005) << id;
    EXPECT_EQ(at(3), BESLAM_LABEL_DYNAMIC) << id;
    EXPECT_EQ(at(0), BESLAM_LABEL_DYNAMIC) << id;  // unknown: dynamic by default
    EXPECT_EQ(mask[5], 0) << id;
    // A NaN box is an error, not a crash.
    beslam_box3d bad = box(8, BESLAM_MOTION_STATIC, 0);
    bad.size[0] = std::nan("");
    const beslam_box_list bad_list{&bad, 1, sizeof(beslam_box3d)};
    EXPECT_EQ(table->generate(inst, &frame, &bad_list, &buf), BESLAM_ERROR_INVALID_ARGUMENT) << id;
    lib.d->destroy(inst);
  }
}

TEST(Plugins, ConfigurationErrors) {
  const beslam_host host{sizeof(beslam_host), BESLAM_ABI_VERSION, nullptr, logSink};
  Library lidar("mask_lidar");
  ASSERT_NE(lidar.d, nullptr);
  {
    const Config config(lidar.d, {});
    const beslam_create_info ci = info(config, &host, false);  // no extrinsics
    void* inst = nullptr;
    EXPECT_EQ(lidar.d->create(&ci, &inst), BESLAM_ERROR_INVALID_CONFIG);
    EXPECT_NE(last_error.find("extrinsics"), std::string::npos) << last_error;
  }
  Library box_lib("mask_box");
  ASSERT_NE(box_lib.d, nullptr);
  {
    const Config config(box_lib.d, {{"canny_low", "200"}, {"canny_high", "100"}});
    const beslam_create_info ci = info(config, &host, false);
    void* inst = nullptr;
    EXPECT_EQ(box_lib.d->create(&ci, &inst), BESLAM_ERROR_INVALID_CONFIG);
  }
}
