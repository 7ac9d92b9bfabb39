// settings.json against include/beslam_orb/options.hpp: every default is written twice, in the settings file
// (the schema the host fills a pipeline's unset settings from, `beslam plugins`) and in Options (what a
// program that makes Options itself gets, and what the tests run with). Here each setting's default text is
// read through the plugin's generated reader (kSettings, the one plugin.cpp uses) and compared, member by
// member, with a default-constructed Options: changing one side alone fails.
#include "beslam_orb/options.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <deque>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "backend_orb_settings.hpp"  // kSettings, generated from settings.json

namespace {

using beslam::orb::Options;

std::string text(bool v) { return v ? "true" : "false"; }
std::string text(int v) { return std::to_string(v); }
std::string text(uint64_t v) { return std::to_string(v); }
std::string text(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.17g", v);
  return buffer;
}
std::string text(const std::string& v) { return "\"" + v + "\""; }
template <class E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
std::string text(E v) {
  return "enum " + std::to_string(static_cast<int>(v));
}

// Each setting's member, by the setting's name (the pipeline's key under backend:).
using Member = std::pair<std::string, std::function<std::string(const Options&)>>;
#define MEMBER(key, path)                              \
  Member {                                             \
    key, [](const Options& o) { return text(o.path); } \
  }

const std::vector<Member>& members() {
  // A module's settings packed on its lines.
  // clang-format off
  static const std::vector<Member> m = {
      MEMBER("features", extractor.features), MEMBER("scale_factor", extractor.scale_factor),
      MEMBER("levels", extractor.levels), MEMBER("fast_initial", extractor.fast_initial),
      MEMBER("fast_fallback", extractor.fast_fallback), MEMBER("static_object_fast", extractor.static_object_fast),
      MEMBER("static_object_budget_share", extractor.static_object_budget_share),
      MEMBER("static_object_weight", static_object_weight),
      MEMBER("fps", tracking.fps), MEMBER("keyframe_floor_ratio", tracking.keyframe_floor_ratio),
      MEMBER("keyframe_min_gap", tracking.keyframe_min_gap), MEMBER("bow_matching", tracking.bow_matching),
      MEMBER("relocalisation", tracking.relocalisation),
      MEMBER("relocalisation_object_check", tracking.relocalisation_object_check),
      MEMBER("keyframe_culling", mapping.keyframe_culling),
      MEMBER("local_ba_max_keyframes", mapping.local_ba_max_keyframes),
      MEMBER("local_ba_solver", mapping.local_ba_solver), MEMBER("triangulation_bow", mapping.triangulation_bow),
      MEMBER("ground_prior", scale.ground_prior), MEMBER("ground_prior_sigma", scale.ground_prior_sigma),
      MEMBER("ground_reference_keyframes", scale.ground_reference_keyframes),
      MEMBER("ground_min_inliers", scale.ground_min_inliers),
      MEMBER("ground_pool_keyframes", scale.ground_pool_keyframes), MEMBER("metric_scale", scale.metric_scale),
      MEMBER("report_map_moves", report_map_moves),
      MEMBER("metric_max_spread", scale.metric_max_spread),
      MEMBER("metric_correction_min", scale.metric_correction_min), MEMBER("object_scale", scale.object_scale),
      MEMBER("object_scale_hold", scale.object_scale_hold), MEMBER("object_range_sigma", scale.object_range_sigma),
      MEMBER("object_range_sigma_per_m", scale.object_range_sigma_per_m), MEMBER("lidar_scale", scale.lidar_scale),
      MEMBER("lidar_reference_keyframes", scale.lidar_reference_keyframes),
      MEMBER("lidar_min_points", scale.lidar_min_points), MEMBER("lidar_points", scale.lidar_points),
      MEMBER("lidar_points_per_keyframe", scale.lidar_points_per_keyframe),
      MEMBER("lidar_range_sigma", scale.lidar_range_sigma),
      MEMBER("lidar_range_sigma_per_m", scale.lidar_range_sigma_per_m),
      MEMBER("object_landmarks", object_landmarks.mode), MEMBER("object_pose_weight", object_landmarks.pose_weight),
      MEMBER("object_surface_weight", object_landmarks.surface_weight),
      MEMBER("object_box_sigma", object_landmarks.box_sigma),
      MEMBER("object_box_sigma_per_m", object_landmarks.box_sigma_per_m),
      MEMBER("object_yaw_sigma_deg", object_landmarks.yaw_sigma_deg),
      MEMBER("object_surface_sigma", object_landmarks.surface_sigma),
      MEMBER("object_surface_gate", object_landmarks.surface_gate),
      MEMBER("threaded_mapping", threading.threaded_mapping),
      MEMBER("concurrent_mapping", threading.concurrent_mapping),
      MEMBER("seed", seed), MEMBER("vocabulary", vocabulary),
      MEMBER("load_map", map_reuse.load_map), MEMBER("save_map", map_reuse.save_map),
      MEMBER("localisation_only", map_reuse.localisation_only),
      MEMBER("loop_closure", loop.enabled), MEMBER("loop_own_stretch_keyframes", loop.own_stretch_keyframes),
      MEMBER("loop_object_check", loop.object_check), MEMBER("loop_global_ba_iterations", loop.global_ba_iterations),
      MEMBER("loop_global_ba_objects", loop.global_ba_objects),
      MEMBER("loop_global_ba_solver", loop.global_ba_solver)};
  // clang-format on
  return m;
}

// Every setting at its schema default, as the host fills a pipeline that sets none.
struct DefaultConfig {
  std::vector<beslam_config_value> values;
  std::deque<std::string> texts;
  DefaultConfig() {
    for (uint32_t i = 0; i < kSettings.size(); ++i) {
      const beslam_config_field& f = kSettings.fields()[i];
      std::string t = f.default_value ? f.default_value : "";
      if (t.size() >= 2 && t.front() == '"' && t.back() == '"') t = t.substr(1, t.size() - 2);
      beslam_config_value v{};
      v.key = f.key;
      v.type = f.type;
      if (f.type == BESLAM_CONFIG_BOOL) {
        v.number = t == "true" ? 1 : 0;
      } else if (f.type == BESLAM_CONFIG_INT || f.type == BESLAM_CONFIG_DOUBLE) {
        v.number = std::stod(t);
      } else {
        texts.push_back(t);
        v.text = texts.back().c_str();
      }
      values.push_back(v);
    }
  }
  beslam::sdk::Config config() const { return {values.data(), static_cast<uint32_t>(values.size())}; }
};

TEST(OptionsDefaults, EverySettingHasItsMemberHere) {
  std::vector<std::string> keys;
  for (uint32_t i = 0; i < kSettings.size(); ++i) keys.emplace_back(kSettings.fields()[i].key);
  for (const std::string& key : keys) {
    bool listed = false;
    for (const Member& m : members()) listed = listed || m.first == key;
    EXPECT_TRUE(listed) << "setting '" << key << "' is not in this test's member list";
  }
  EXPECT_EQ(members().size(), keys.size()) << "the member list names a setting settings.json does not have";
}

TEST(OptionsDefaults, SettingsJsonDefaultsAreTheStructsDefaults) {
  const DefaultConfig defaults;
  const Options from_schema = kSettings.read(defaults.config());
  const Options from_struct{};
  for (const auto& [key, member] : members())
    EXPECT_EQ(member(from_schema), member(from_struct))
        << "setting '" << key << "': settings.json's default (left) is not Options' (right)";
  std::string error;
  EXPECT_TRUE(from_struct.validate(&error)) << error;
}

}  // namespace
