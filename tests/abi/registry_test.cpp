// The host against good and deliberately broken plugin libraries: every refusal names the file and the
// cause, and no exception from a plugin crosses the C ABI.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "beslam/common/error.hpp"
#include "beslam/registry/instance.hpp"
#include "beslam/registry/registry.hpp"

using beslam::registry::Registry;

namespace {

std::string fixture(const std::string& name) { return std::string(FIXTURE_DIR) + "/" + name + ".so"; }

// Loads a library expecting a refusal; returns the message.
std::string refusal(const std::string& path) {
  Registry registry;
  try {
    registry.loadLibrary(path);
  } catch (const beslam::Error& e) {
    return e.what();
  }
  ADD_FAILURE() << path << " was accepted";
  return {};
}

beslam_create_info createInfo(const beslam::registry::HostLog& log, const std::vector<beslam_config_value>& config) {
  beslam_create_info info{};
  info.struct_size = sizeof(info);
  info.host = log.host();
  info.config = config.data();
  info.config_count = static_cast<uint32_t>(config.size());
  info.camera = {sizeof(beslam_camera), 64, 48, 0, 50, 50, 32, 24};
  return info;
}

beslam_config_value number(const char* key, int32_t type, double v) {
  beslam_config_value c{};
  c.key = key;
  c.type = type;
  c.number = v;
  return c;
}

}  // namespace

TEST(Registry, RefusesWrongMajorVersion) {
  const std::string message = refusal(fixture("wrong_major"));
  EXPECT_NE(message.find("wrong_major.so"), std::string::npos) << message;
  EXPECT_NE(message.find("ABI 2.0"), std::string::npos) << message;
  EXPECT_NE(message.find("major versions must match"), std::string::npos) << message;
}

TEST(Registry, RefusesShortDescriptor) {
  const std::string message = refusal(fixture("short_struct"));
  EXPECT_NE(message.find("short_struct.so"), std::string::npos) << message;
  EXPECT_NE(message.find("struct_size 16"), std::string::npos) << message;
}

TEST(Registry, RefusesMissingEntryPoint) {
  const std::string message = refusal(fixture("missing_function"));
  EXPECT_NE(message.find("missing_function.so"), std::string::npos) << message;
  EXPECT_NE(message.find("missing symbol beslam_plugin_list"), std::string::npos) << message;
}

TEST(Registry, RefusesLibraryThatIsNotAPlugin) {
  const std::string message = refusal(fixture("not_a_plugin"));
  EXPECT_NE(message.find("not a BE-SLAM plugin"), std::string::npos) << message;
}

TEST(Registry, RefusesNullFunctionInTable) {
  const std::string message = refusal(fixture("null_function"));
  EXPECT_NE(message.find("null_function.so"), std::string::npos) << message;
  EXPECT_NE(message.find("function of its table is null"), std::string::npos) << message;
}

TEST(Registry, RefusesMissingFileAndNonLibrary) {
  EXPECT_NE(refusal("/nonexistent/plugin.so").find("no such plugin library"), std::string::npos);
  const std::string text = std::string(FIXTURE_DIR) + "/../abi_text_file.so";
  { FILE* f = std::fopen(text.c_str(), "w"); ASSERT_NE(f, nullptr); std::fputs("not an ELF file", f); std::fclose(f); }
  EXPECT_NE(refusal(text).find("abi_text_file.so"), std::string::npos);
}

TEST(Registry, ScanCollectsProblemsAndKeepsGoodPlugins) {
  Registry registry;
  registry.addSearchPath(FIXTURE_DIR);
  registry.scan();
  EXPECT_EQ(registry.problems().size(), 5u);
  EXPECT_NO_THROW(registry.find("fixture_boxes", BESLAM_KIND_DETECTOR));
  try {
    registry.find("fixture_boxes", BESLAM_KIND_BACKEND);
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("is a detector, not a backend"), std::string::npos);
  }
  try {
    registry.find("no_such_plugin", BESLAM_KIND_DETECTOR);
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("known: fixture_throwing, fixture_boxes"), std::string::npos) << e.what();
  }
}

TEST(Registry, ListsSchemaOfSdkPlugin) {
  Registry registry;
  registry.loadLibrary(fixture("sdk_fixtures"));
  const auto& p = registry.find("fixture_boxes");
  EXPECT_EQ(p.version, "0.1.0");
  ASSERT_EQ(p.fields.size(), 5u);
  EXPECT_EQ(p.fields[1].key, "depth");
  EXPECT_EQ(p.fields[1].type, BESLAM_CONFIG_DOUBLE);
  EXPECT_DOUBLE_EQ(p.fields[1].min_value, 0.5);
  EXPECT_EQ(p.fields[3].choices, "car|pedestrian");
}

TEST(Registry, ExceptionInCreateBecomesAnErrorWithItsMessage) {
  Registry registry;
  registry.loadLibrary(fixture("sdk_fixtures"));
  beslam::registry::HostLog log;
  const std::vector<beslam_config_value> none;
  try {
    beslam::registry::DetectorInstance d(registry.find("fixture_throwing"), createInfo(log, none), log);
    FAIL() << "create should fail";
  } catch (const beslam::Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("fixture_throwing"), std::string::npos) << m;
    EXPECT_NE(m.find("create failed (runtime error): constructor exploded on purpose"), std::string::npos) << m;
  }
}

TEST(Registry, MissingConfigValueIsInvalidConfig) {
  Registry registry;
  registry.loadLibrary(fixture("sdk_fixtures"));
  beslam::registry::HostLog log;
  const std::vector<beslam_config_value> partial = {number("emit_nan", BESLAM_CONFIG_BOOL, 0)};
  try {
    beslam::registry::DetectorInstance d(registry.find("fixture_boxes"), createInfo(log, partial), log);
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("invalid configuration"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'depth' is missing"), std::string::npos) << e.what();
  }
}

TEST(Registry, DetectAndClassifyRoundTrip) {
  Registry registry;
  registry.loadLibrary(fixture("sdk_fixtures"));
  beslam::registry::HostLog log;
  const double size[] = {4.0, 1.8, 1.5};
  beslam_config_value list{};
  list.key = "size";
  list.type = BESLAM_CONFIG_DOUBLE_LIST;
  list.list = size;
  list.list_size = 3;
  beslam_config_value cls{};
  cls.key = "class_name";
  cls.type = BESLAM_CONFIG_STRING;
  cls.text = "car";
  const std::vector<beslam_config_value> config = {number("emit_nan", BESLAM_CONFIG_BOOL, 0),
                                                   number("depth", BESLAM_CONFIG_DOUBLE, 12.5),
                                                   number("count", BESLAM_CONFIG_INT, 3), cls, list};
  beslam::registry::DetectorInstance detector(registry.find("fixture_boxes"), createInfo(log, config), log);
  beslam::registry::MotionCheckerInstance checker(registry.find("fixture_all_static"), createInfo(log, {}), log);

  std::vector<uint8_t> pixels(64 * 48, 128);
  beslam_frame frame{};
  frame.struct_size = sizeof(frame);
  frame.gray = {pixels.data(), 64, 48, 64, BESLAM_PIXEL_GRAY8};
  std::vector<beslam_box3d> boxes = detector.detect(frame);
  ASSERT_EQ(boxes.size(), 3u);
  EXPECT_DOUBLE_EQ(boxes[0].center_cam[2], 12.5);
  EXPECT_EQ(boxes[0].track_id, -1);
  EXPECT_DOUBLE_EQ(boxes[2].size[1], 1.8);

  checker.classify(frame, Eigen::Isometry3d::Identity(), boxes);
  EXPECT_EQ(boxes[1].track_id, 8);
  EXPECT_EQ(boxes[1].motion_state, BESLAM_MOTION_STATIC);
  checker.classify(frame, std::nullopt, boxes);
  EXPECT_EQ(boxes[1].motion_state, BESLAM_MOTION_UNKNOWN);

  // An exception inside a call becomes a status and a message, never a crash.
  beslam_frame empty{};
  empty.struct_size = sizeof(empty);
  try {
    detector.detect(empty);
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("detect failed (invalid argument): frame without a grey image"),
              std::string::npos)
        << e.what();
  }
}

TEST(Registry, FindsBuiltInPluginsThroughEnvironment) {
  // ctest sets BESLAM_PLUGIN_PATH to the built-in plugin folder.
  Registry registry;
  registry.addSearchPath(PLUGIN_DIR);
  registry.scan();
  EXPECT_TRUE(registry.problems().empty()) << registry.problems().front();
  EXPECT_NO_THROW(registry.find("backend_pose_replay", BESLAM_KIND_BACKEND));
}
