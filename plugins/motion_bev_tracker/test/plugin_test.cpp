// The motion_bev_tracker plugin through the host's registry (schema, configuration errors, in-place
// classification), and backend_pose_replay's handling of malformed pose files, as the motion pipeline
// (configs/kitti_tracking_motion.yaml) uses both.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "beslam/formats/error.hpp"
#include "beslam/test/plugin_harness.hpp"

namespace fs = std::filesystem;
using beslam::test::PluginHarness;

namespace {

std::string pluginLib(const char* name) { return std::string(PLUGIN_DIR) + "/" + name + ".so"; }

beslam_box3d car(double x, double z) {
  beslam_box3d b{};
  b.class_id = BESLAM_CLASS_CAR;
  b.track_id = -1;
  b.center_cam[0] = x, b.center_cam[1] = 1.0, b.center_cam[2] = z;
  b.size[0] = 4.2, b.size[1] = 1.8, b.size[2] = 1.5;
  b.score = 0.9f;
  return b;
}

fs::path tempDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("beslam_motion_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(MotionPlugin, ClassifiesParkedAndMovingCarsInPlace) {
  PluginHarness h(pluginLib("motion_bev_tracker"));
  const auto& plugin = h.plugin("motion_bev_tracker");
  EXPECT_EQ(plugin.kind, BESLAM_KIND_MOTION_CHECKER);
  const auto& config = h.config("motion_bev_tracker", {{"stop_dwell", "4"}});
  beslam::registry::MotionCheckerInstance checker(plugin, h.info(config), h.log);
  std::vector<beslam_box3d> boxes;
  for (int k = 0; k < 30; ++k) {
    const double ego_z = 0.8 * k;  // 8 m/s
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().z() = ego_z;
    boxes = {car(4.0, 30.0 - ego_z), car(-3.0, 12.0 + 1.2 * k - ego_z)};  // parked; moving at 12 m/s
    checker.classify(PluginHarness::frame(k, 0.1 * k), T, boxes);
    ASSERT_EQ(boxes.size(), 2u);
  }
  EXPECT_EQ(boxes[0].motion_state, BESLAM_MOTION_STATIC);
  EXPECT_EQ(boxes[1].motion_state, BESLAM_MOTION_DYNAMIC);
  EXPECT_GE(boxes[0].track_id, 0);
  EXPECT_NE(boxes[0].track_id, boxes[1].track_id);
  // Without a pose the boxes are still tracked but unknown.
  boxes = {car(4.0, 10.0)};
  beslam::registry::MotionCheckerInstance fresh(plugin, h.info(config), h.log);
  fresh.classify(PluginHarness::frame(0, 0.0), std::nullopt, boxes);
  EXPECT_EQ(boxes[0].motion_state, BESLAM_MOTION_UNKNOWN);
  EXPECT_GE(boxes[0].track_id, 0);
}

TEST(MotionPlugin, NonFiniteBoxIsAnError) {
  PluginHarness h(pluginLib("motion_bev_tracker"));
  const auto& config = h.config("motion_bev_tracker", {});
  beslam::registry::MotionCheckerInstance checker(h.plugin("motion_bev_tracker"), h.info(config), h.log);
  std::vector<beslam_box3d> boxes = {car(std::nan(""), 10)};
  EXPECT_THROW(checker.classify(PluginHarness::frame(0, 0.0), Eigen::Isometry3d::Identity(), boxes), beslam::Error);
}

TEST(MotionPlugin, InconsistentSettingsAreAConfigError) {
  PluginHarness h(pluginLib("motion_bev_tracker"));
  const auto& config = h.config("motion_bev_tracker", {{"association", "magic"}});
  try {
    beslam::registry::MotionCheckerInstance checker(h.plugin("motion_bev_tracker"), h.info(config), h.log);
    FAIL() << "expected a configuration error";
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("association"), std::string::npos) << e.what();
  }
}

// backend_pose_replay is the pose source of the motion pipeline: each malformed pose file must stop the
// run at creation with the file (and line) named.
TEST(MotionPoseFiles, MalformedPoseFilesAreReportedWithFileAndLine) {
  const std::string lib = pluginLib("backend_pose_replay");
  if (!fs::exists(lib)) GTEST_SKIP() << "backend_pose_replay is not built (" << lib << ")";
  PluginHarness h(lib);
  const fs::path dir = tempDir("poses");
  const std::string good = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  struct Case {
    std::string name, text;
    int line;  // 0: the file as a whole
  };
  const std::vector<Case> cases = {
      {"short_row.txt", good + "1 0 0 0 0 1 0 0 0 0 1\n", 2},
      {"not_a_number.txt", good + "1 0 0 x 0 1 0 0 0 0 1 0\n", 2},
      {"nan.txt", good + "1 0 0 nan 0 1 0 0 0 0 1 0\n", 2},
      {"not_a_rotation.txt", good + "2 0 0 0 0 1 0 0 0 0 1 0\n", 2},
      {"tum_zero_quaternion.txt", "0.0 1 2 3 0 0 0 0\n", 1},
      {"tum_time_goes_back.txt", "1.0 1 2 3 0 0 0 1\n0.5 1 2 3 0 0 0 1\n", 0},  // named by pose number
      {"empty.txt", "# nothing\n", 0},
  };
  for (const Case& c : cases) {
    const fs::path file = dir / c.name;
    std::ofstream(file) << c.text;
    const auto& config = h.config("backend_pose_replay", {{"poses", file.string()}});
    try {
      beslam::registry::BackendInstance backend(h.plugin("backend_pose_replay"), h.info(config), h.log);
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const beslam::Error& e) {
      const std::string what = e.what();
      const std::string where = c.line > 0 ? file.string() + ":" + std::to_string(c.line) + ":" : file.string();
      EXPECT_NE(what.find(where), std::string::npos) << c.name << ": " << what;
    }
  }
  const auto& missing = h.config("backend_pose_replay", {{"poses", (dir / "absent.txt").string()}});
  EXPECT_THROW(beslam::registry::BackendInstance(h.plugin("backend_pose_replay"), h.info(missing), h.log),
               beslam::Error);
  fs::remove_all(dir);
}
