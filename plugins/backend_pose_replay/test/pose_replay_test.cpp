// backend_pose_replay through the host's registry: KITTI rows by frame index, TUM rows by nearest
// timestamp within max_time_diff, frames without a pose reported (never invented), keyframe spacing,
// and malformed pose files named with their line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "beslam/common/error.hpp"
#include "beslam/test/plugin_harness.hpp"

namespace fs = std::filesystem;
using beslam::test::PluginHarness;

namespace {

const std::string kLib = std::string(PLUGIN_DIR) + "/backend_pose_replay.so";

std::string write(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / ("beslam_pose_replay_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path.string();
}

}  // namespace

TEST(PoseReplay, KittiRowsByFrameIndex) {
  PluginHarness h(kLib);
  const std::string poses =
      write("kitti.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 2\n1 0 0 2 0 1 0 0 0 0 1 4\n");
  const auto& config = h.config("backend_pose_replay", {{"poses", poses}, {"keyframe_interval", "2"}});
  beslam::registry::BackendInstance backend(h.plugin("backend_pose_replay"), h.info(config), h.log);
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
  fs::remove(poses);
}

TEST(PoseReplay, TumRowsByNearestTimestamp) {
  PluginHarness h(kLib);
  const std::string poses =
      write("tum.txt", "# t x y z qx qy qz qw\n10.00 0 0 0 0 0 0 1\n10.10 0 0 1 0 0 0 1\n10.30 0 0 3 0 0 0 1\n");
  const auto& config = h.config("backend_pose_replay", {{"poses", poses}, {"max_time_diff", "0.02"}});
  beslam::registry::BackendInstance backend(h.plugin("backend_pose_replay"), h.info(config), h.log);
  const auto at = [&](double t) { return backend.predictPose(PluginHarness::frame(0, t)); };
  ASSERT_TRUE(at(10.11).has_value());
  EXPECT_DOUBLE_EQ(at(10.11)->translation().z(), 1.0);
  EXPECT_DOUBLE_EQ(at(10.29)->translation().z(), 3.0);
  EXPECT_FALSE(at(10.20).has_value());  // 0.1 s from both neighbours: no pose is invented
  EXPECT_FALSE(at(9.0).has_value());
  fs::remove(poses);
}

TEST(PoseReplay, MalformedFilesAreNamedWithTheirLine) {
  PluginHarness h(kLib);
  const auto error = [&](const std::string& text) {
    const std::string poses = write("bad.txt", text);
    const auto& config = h.config("backend_pose_replay", {{"poses", poses}});
    std::string message;
    try {
      beslam::registry::BackendInstance backend(h.plugin("backend_pose_replay"), h.info(config), h.log);
    } catch (const beslam::Error& e) {
      message = e.what();
    }
    fs::remove(poses);
    return message;
  };
  EXPECT_NE(error("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 nan 0 0 1 0\n").find("bad.txt:2"), std::string::npos);
  EXPECT_NE(error("1 2 3\n").find("bad.txt"), std::string::npos);
  EXPECT_NE(error("1.0 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n").find("timestamps must increase"), std::string::npos);
  EXPECT_NE(error("").find("bad.txt"), std::string::npos);
}
