// The SDK as a third party gets it: install the project into a temporary prefix, build
// sdk/template OUT OF TREE against the installed beslam_sdk package, then have the host list the
// plugin and run it.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "beslam/common/error.hpp"
#include "beslam/registry/instance.hpp"
#include "beslam/registry/registry.hpp"

namespace fs = std::filesystem;

namespace {

int shell(const std::string& command, const fs::path& log) {
  const std::string full = command + " > " + log.string() + " 2>&1";
  return std::system(full.c_str());
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class TemplateBuild : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("beslam_sdk_template_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    const fs::path prefix = root_ / "prefix";
    ASSERT_EQ(shell("cmake --install " + std::string(BESLAM_BINARY_DIR) + " --prefix " + prefix.string(),
                    root_ / "install.log"), 0)
        << slurp(root_ / "install.log");
    ASSERT_TRUE(fs::exists(prefix / "include/beslam/sdk/sdk.hpp"));
    // Configure and build the template from the INSTALLED copy, as a plugin author would.
    const fs::path src = prefix / "share/beslam/plugin-template";
    ASSERT_TRUE(fs::exists(src / "CMakeLists.txt"));
    ASSERT_EQ(shell("cmake -S " + src.string() + " -B " + (root_ / "build").string() +
                        " -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=" + prefix.string() +
                        " && cmake --build " + (root_ / "build").string(),
                    root_ / "build.log"), 0)
        << slurp(root_ / "build.log");
    plugin_dir_ = root_ / "build" / "plugins";
    built_ = fs::exists(plugin_dir_ / "mask_rect.so");
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }

  static inline fs::path root_, plugin_dir_;
  static inline bool built_ = false;
};

}  // namespace

TEST_F(TemplateBuild, HostLoadsAndRunsTheOutOfTreePlugin) {
  ASSERT_TRUE(built_);
  beslam::registry::Registry registry;
  registry.addSearchPath(plugin_dir_.string());
  registry.scan();
  ASSERT_TRUE(registry.problems().empty()) << registry.problems().front();
  const auto& plugin = registry.find("mask_rect", BESLAM_KIND_MASK_GENERATOR);
  EXPECT_EQ(plugin.version, "1.0.0");
  ASSERT_EQ(plugin.fields.size(), 3u);

  beslam::registry::HostLog log;
  std::vector<beslam_config_value> config(3);
  config[0] = {"margin_px", BESLAM_CONFIG_INT, 0, 0, nullptr, nullptr, 0};
  config[1] = {"unknown_is_dynamic", BESLAM_CONFIG_BOOL, 0, 1, nullptr, nullptr, 0};
  config[2] = {"min_depth", BESLAM_CONFIG_DOUBLE, 0, 0.5, nullptr, nullptr, 0};
  beslam_create_info info{};
  info.struct_size = sizeof(info);
  info.host = log.host();
  info.config = config.data();
  info.config_count = 3;
  info.camera = {sizeof(beslam_camera), 200, 100, 0, 100, 100, 100, 50};
  beslam::registry::MaskGeneratorInstance masker(plugin, info, log);

  // A 2 m cube 10 m ahead, centred: it spans u = 100 +- 100*1/9..1/11 -> about [89, 111].
  beslam_box3d box{};
  box.class_id = BESLAM_CLASS_CAR;
  box.track_id = 4;
  box.motion_state = BESLAM_MOTION_STATIC;
  box.center_cam[2] = 10;
  box.size[0] = box.size[1] = box.size[2] = 2;
  cv::Mat gray(100, 200, CV_8UC1, cv::Scalar(0));
  beslam_frame frame{};
  frame.struct_size = sizeof(frame);
  frame.gray = {gray.data, 200, 100, 200, BESLAM_PIXEL_GRAY8};
  cv::Mat mask = cv::Mat::zeros(100, 200, CV_16UC1);
  beslam_mask_buffer buffer{reinterpret_cast<uint16_t*>(mask.data), 200, 100, static_cast<int32_t>(mask.step[0]), 0};
  masker.generate(frame, {box}, buffer);
  EXPECT_EQ(mask.at<uint16_t>(50, 100), BESLAM_LABEL_STATIC_BASE + 4);
  EXPECT_EQ(mask.at<uint16_t>(50, 80), 0);
  const cv::Rect filled = cv::boundingRect(mask > 0);
  EXPECT_NEAR(filled.x, 89, 1);
  EXPECT_NEAR(filled.x + filled.width - 1, 111, 1);

  // A NaN box is refused with a message, not a crash.
  box.center_cam[2] = std::nan("");
  EXPECT_THROW(masker.generate(frame, {box}, buffer), beslam::Error);
}

TEST_F(TemplateBuild, BeslamPluginsListsIt) {
  ASSERT_TRUE(built_);
  const fs::path out = root_ / "plugins.txt";
  ASSERT_EQ(shell(std::string(BESLAM_BINARY_DIR) + "/bin/beslam plugins --plugin-path " + plugin_dir_.string(), out), 0)
      << slurp(out);
  const std::string text = slurp(out);
  EXPECT_NE(text.find("mask_rect  (mask_generator, version 1.0.0, ABI 1.2)"), std::string::npos) << text;
  EXPECT_NE(text.find("backend_pose_replay"), std::string::npos) << text;
}
