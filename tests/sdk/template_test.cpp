// The SDK as a third party gets it: install the project into a temporary prefix, build
// sdk/template OUT OF TREE against the installed beslam_sdk package (the mask generator on the SDK
// headers, the replay detector on the SDK's formats library too), then have the host list the plugins
// and run them.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/registry/instance.hpp"
#include "beslam/registry/registry.hpp"
#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;

namespace {

int shell(const std::string& command, const fs::path& log) {
  const std::string full = command + " > " + log.string() + " 2>&1";
  return std::system(full.c_str());
}

using beslam::test::readText;

class TemplateBuild : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("beslam_sdk_template_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    const fs::path prefix = root_ / "prefix";
    ASSERT_EQ(shell("cmake --install " + std::string(BESLAM_BINARY_DIR) + " --prefix " + prefix.string(),
                    root_ / "install.log"),
              0)
        << readText(root_ / "install.log");
    ASSERT_TRUE(fs::exists(prefix / "include/beslam/sdk/sdk.hpp"));
    // Configure and build the template from the INSTALLED copy, as a plugin author would.
    const fs::path src = prefix / "share/beslam/plugin-template";
    ASSERT_TRUE(fs::exists(src / "CMakeLists.txt"));
    ASSERT_EQ(shell("cmake -S " + src.string() + " -B " + (root_ / "build").string() +
                        " -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=" + prefix.string() + " && cmake --build " +
                        (root_ / "build").string(),
                    root_ / "build.log"),
              0)
        << readText(root_ / "build.log");
    plugin_dir_ = root_ / "build" / "plugins";
    built_ = fs::exists(plugin_dir_ / "mask_rect.so") && fs::exists(plugin_dir_ / "label_replay.so");
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }

  // Each test starts with the built plugins scanned by a fresh registry (with no problems).
  void SetUp() override {
    ASSERT_TRUE(built_);
    registry_.addSearchPath(plugin_dir_.string());
    registry_.scan();
    ASSERT_TRUE(registry_.problems().empty()) << registry_.problems().front();
  }

  beslam::registry::Registry registry_;

  static inline fs::path root_, plugin_dir_;
  static inline bool built_ = false;
};

}  // namespace

TEST_F(TemplateBuild, HostLoadsAndRunsTheOutOfTreePlugin) {
  beslam::registry::Registry& registry = registry_;
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

// The template declares its settings as data (sdk/template/mask_rect.settings.json); the installed SDK's
// beslam_add_plugin generated the header with Options and kSettings, which is the schema the host sees.
TEST_F(TemplateBuild, TheSettingsFileIsTheSchema) {
  EXPECT_TRUE(fs::exists(root_ / "build" / "mask_rect_settings" / "mask_rect_settings.hpp"));
  const auto& plugin = registry_.find("mask_rect", BESLAM_KIND_MASK_GENERATOR);
  ASSERT_EQ(plugin.fields.size(), 3u);
  EXPECT_EQ(plugin.fields[0].key, "margin_px");
  EXPECT_EQ(plugin.fields[0].type, BESLAM_CONFIG_INT);
  EXPECT_EQ(plugin.fields[0].default_value, "4");
  EXPECT_EQ(plugin.fields[0].min_value, 0);
  EXPECT_EQ(plugin.fields[0].max_value, 200);
  EXPECT_EQ(plugin.fields[0].doc, "pixels added on every side of the rectangle");
  EXPECT_EQ(plugin.fields[1].type, BESLAM_CONFIG_BOOL);
  EXPECT_EQ(plugin.fields[2].type, BESLAM_CONFIG_DOUBLE);
}

TEST_F(TemplateBuild, BeslamPluginsListsIt) {
  const fs::path out = root_ / "plugins.txt";
  ASSERT_EQ(shell(std::string(BESLAM_BINARY_DIR) + "/bin/beslam plugins --plugin-path " + plugin_dir_.string(), out), 0)
      << readText(out);
  const std::string text = readText(out);
  // Built against this tree's SDK: this tree's ABI version.
  const std::string abi = std::to_string(BESLAM_ABI_VERSION_MAJOR) + "." + std::to_string(BESLAM_ABI_VERSION_MINOR);
  EXPECT_NE(text.find("mask_rect  (mask_generator, version 1.0.0, ABI " + abi + ")"), std::string::npos) << text;
  EXPECT_NE(text.find("backend_pose_replay"), std::string::npos) << text;
}

TEST_F(TemplateBuild, TheOutOfTreeReplayPluginReadsLabelsThroughTheSdkFormats) {
  beslam::registry::Registry& registry = registry_;
  const auto& plugin = registry.find("label_replay", BESLAM_KIND_DETECTOR);
  ASSERT_EQ(plugin.fields.size(), 3u);
  EXPECT_EQ(plugin.fields[2].choices, "empty|error");

  const fs::path labels = root_ / "labels";
  fs::create_directories(labels);
  std::ofstream(labels / "000000.txt") << "Car 0.00 0 -1.57 100 120 200 180 1.50 1.60 3.90 2.00 1.70 12.00 0.10 0.9\n"
                                       << "DontCare -1 -1 -10 0 0 10 10 -1 -1 -1 -1000 -1000 -1000 -10\n"
                                       << "Pedestrian 0.00 0 0.2 10 10 20 40 1.80 0.60 0.80 -3.00 1.60 8.00 0.00 0.2\n";
  std::ofstream(labels / "000002.txt") << "Car 0.00 0 -1.57 100 120 200 180 1.50 1.60 3.90 2.00 1.70\n";

  beslam::registry::HostLog log;
  const std::string folder = labels.string();
  std::vector<beslam_config_value> config(3);
  config[0] = {"folder", BESLAM_CONFIG_PATH, 0, 0, folder.c_str(), nullptr, 0};
  config[1] = {"min_score", BESLAM_CONFIG_DOUBLE, 0, 0.5, nullptr, nullptr, 0};
  config[2] = {"missing", BESLAM_CONFIG_STRING, 0, 0, "empty", nullptr, 0};
  beslam_create_info info{};
  info.struct_size = sizeof(info);
  info.host = log.host();
  info.config = config.data();
  info.config_count = 3;
  beslam::registry::DetectorInstance detector(plugin, info, log);

  beslam_frame frame{};
  frame.struct_size = sizeof(frame);
  frame.index = 0;
  const std::vector<beslam_box3d> boxes = detector.detect(frame);
  ASSERT_EQ(boxes.size(), 1u);  // DontCare skipped, the pedestrian below min_score
  EXPECT_EQ(boxes[0].class_id, BESLAM_CLASS_CAR);
  EXPECT_DOUBLE_EQ(boxes[0].center_cam[1], 1.70 - 1.50 / 2);  // KITTI's bottom centre -> geometric centre
  EXPECT_DOUBLE_EQ(boxes[0].size[0], 3.90);
  EXPECT_FLOAT_EQ(boxes[0].score, 0.9f);
  EXPECT_EQ(boxes[0].track_id, -1);

  frame.index = 1;
  EXPECT_TRUE(detector.detect(frame).empty());  // no label file: no objects
  frame.index = 2;                              // a 13-field row: the error names the file and the line
  try {
    detector.detect(frame);
    FAIL() << "a malformed label row was accepted";
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("000002.txt:1: object label row has 13 fields, expected 15 or 16"),
              std::string::npos)
        << e.what();
  }
}

// The built-in plugins a newcomer is most likely to copy (the replay detectors and the pose-replay
// backend) build out of tree from the installed SDK alone: their own folders, added to a project that
// knows nothing but find_package(beslam_sdk); no host library exists there to link.
TEST_F(TemplateBuild, BuiltInReplayPluginsBuildFromTheInstalledSdkAlone) {
  const fs::path project = root_ / "replays";
  fs::create_directories(project);
  std::ofstream(project / "CMakeLists.txt") << "cmake_minimum_required(VERSION 3.19)\n"
                                            << "project(builtin_replays CXX)\n"
                                            << "find_package(beslam_sdk REQUIRED)\n"
                                            << "if(TARGET beslam_registry OR TARGET beslam_datasets)\n"
                                            << "  message(FATAL_ERROR \"a host library is visible\")\n"
                                            << "endif()\n"
                                            << "foreach(p detector_replay detector_oracle backend_pose_replay)\n"
                                            << "  add_subdirectory(" << BESLAM_SOURCE_DIR << "/plugins/${p} ${p})\n"
                                            << "endforeach()\n";
  ASSERT_EQ(shell("cmake -S " + project.string() + " -B " + (project / "build").string() +
                      " -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=" + (root_ / "prefix").string() +
                      " && cmake --build " + (project / "build").string() + " -j2",
                  root_ / "replays.log"),
            0)
      << readText(root_ / "replays.log");
  const fs::path plugins = project / "build" / "plugins";
  const fs::path out = root_ / "replays_listed.txt";
  ASSERT_EQ(shell(std::string(BESLAM_BINARY_DIR) + "/bin/beslam plugins --json --plugin-path " + plugins.string(), out),
            0)
      << readText(out);
  const std::string text = readText(out);
  for (const char* id : {"detector_replay", "detector_oracle", "backend_pose_replay"})
    EXPECT_NE(text.find(plugins.string() + "/" + id + ".so"), std::string::npos) << id << " not built out of tree:\n"
                                                                                 << text;
}
