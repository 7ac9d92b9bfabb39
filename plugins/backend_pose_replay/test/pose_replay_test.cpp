// backend_pose_replay through the host's registry: KITTI rows by frame index, TUM rows by nearest
// timestamp within max_time_diff, frames without a pose reported (never invented), keyframe spacing,
// and malformed pose files named with their line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>

#include "beslam/formats/error.hpp"
#include "beslam/test/plugin_harness.hpp"
#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;
using beslam::test::PluginHarness;

namespace {

const std::string kLib = std::string(PLUGIN_DIR) + "/backend_pose_replay.so";

// A scratch folder and the plugin loaded through the host's registry.
class PoseReplay : public ::testing::Test {
 protected:
  // The backend replaying `text` (written to `name`) with the given extra settings.
  std::unique_ptr<beslam::registry::BackendInstance> open(const std::string& name, const std::string& text,
                                                          std::map<std::string, std::string> settings = {}) {
    settings["poses"] = dir_.write(name, text);
    const auto& config = harness_.config("backend_pose_replay", settings);
    return std::make_unique<beslam::registry::BackendInstance>(harness_.plugin("backend_pose_replay"),
                                                               harness_.info(config), harness_.log);
  }

  beslam::test::TempDir dir_;
  PluginHarness harness_{kLib};
};

}  // namespace

TEST_F(PoseReplay, KittiRowsByFrameIndex) {
  auto instance = open("kitti.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 2\n1 0 0 2 0 1 0 0 0 0 1 4\n",
                       {{"keyframe_interval", "2"}});
  beslam::registry::BackendInstance& backend = *instance;
  for (int64_t i = 0; i < 4; ++i) {
    const beslam_frame frame = PluginHarness::frame(i, 0.1 * static_cast<double>(i));
    const auto predicted = backend.predictPose(frame);
    const auto out = backend.track(frame, beslam_image_view{}, {});
    if (i < 3) {
      ASSERT_TRUE(predicted.has_value());
      EXPECT_DOUBLE_EQ(predicted->translation().z(), 2.0 * static_cast<double>(i));
      EXPECT_EQ(out.result.state, BESLAM_TRACKING_OK);
      EXPECT_EQ(out.result.is_keyframe, i % 2 == 0 ? 1 : 0);
    } else {
      EXPECT_FALSE(predicted.has_value());
      EXPECT_EQ(out.result.state, BESLAM_TRACKING_LOST);
    }
  }
  EXPECT_EQ(backend.trajectory(BESLAM_TRAJECTORY_FINAL).size(), 3u);
  EXPECT_EQ(backend.trajectory(BESLAM_TRAJECTORY_KEYFRAMES).size(), 2u);
}

TEST_F(PoseReplay, TumRowsByNearestTimestamp) {
  auto instance =
      open("tum.txt", "# t x y z qx qy qz qw\n10.00 0 0 0 0 0 0 1\n10.10 0 0 1 0 0 0 1\n10.30 0 0 3 0 0 0 1\n",
           {{"max_time_diff", "0.02"}});
  beslam::registry::BackendInstance& backend = *instance;
  const auto at = [&](double t) { return backend.predictPose(PluginHarness::frame(0, t)); };
  ASSERT_TRUE(at(10.11).has_value());
  EXPECT_DOUBLE_EQ(at(10.11)->translation().z(), 1.0);
  EXPECT_DOUBLE_EQ(at(10.29)->translation().z(), 3.0);
  EXPECT_FALSE(at(10.20).has_value());  // 0.1 s from both neighbours: no pose is invented
  EXPECT_FALSE(at(9.0).has_value());
}

TEST_F(PoseReplay, MalformedFilesAreNamedWithTheirLine) {
  const auto error = [&](const std::string& text) {
    try {
      open("bad.txt", text);
    } catch (const beslam::Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 nan 0 0 1 0\n").find("bad.txt:2"), std::string::npos);
  EXPECT_NE(error("1 2 3\n").find("bad.txt"), std::string::npos);
  EXPECT_NE(error("1.0 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n").find("timestamps must increase"), std::string::npos);
  EXPECT_NE(error("").find("bad.txt"), std::string::npos);
}
