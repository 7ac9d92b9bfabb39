// nuScenes results: the global -> ego -> camera transform and back, the token/ego-pose files, the JSON
// reader and every malformed-input path.
#include "beslam/detector_replay/nuscenes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace beslam::detector_replay;
using json = nlohmann::json;

namespace {

using Dir = beslam::test::TempDir;

// The nuScenes CAM_FRONT extrinsic (ego x forward, y left, z up -> camera x right, y down, z forward).
const std::vector<double> kCamFront = {1.70079, 0.01594, 1.51095, 0.4998, -0.5030, 0.4997, -0.4969};

Eigen::Isometry3d egoPose(double x, double y, double yaw, double pitch = 0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.3);
  return T;
}

json box(const std::string& token, Eigen::Vector3d t, double yaw, const std::string& name = "car", double score = 0.8) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return json{{"sample_token", token},    {"translation", {t.x(), t.y(), t.z()}},
              {"size", {1.9, 4.6, 1.7}},  {"rotation", {q.w(), q.x(), q.y(), q.z()}},
              {"velocity", {3.0, -1.0}},  {"detection_name", name},
              {"detection_score", score}, {"attribute_name", "vehicle.moving"}};
}

}  // namespace

TEST(NuScenesTransform, GlobalToCameraAndBack) {
  const Eigen::Isometry3d T_ego_cam = poseFromTranslationQuaternion(kCamFront, "cam");
  for (const Eigen::Isometry3d& T_global_ego :
       {egoPose(0, 0, 0), egoPose(400.5, 1100.2, 2.1), egoPose(-30, 12, -0.7)}) {
    const Eigen::Isometry3d T_cam_global = T_ego_cam.inverse() * T_global_ego.inverse();
    // A car 15 m ahead of the ego, 2 m to its left, heading 30 degrees left of the ego's heading.
    NuScenesBox b;
    const double ego_yaw = std::atan2(T_global_ego.linear()(1, 0), T_global_ego.linear()(0, 0));
    b.translation = T_global_ego * Eigen::Vector3d(15, 2, 0.8);
    b.rotation = Eigen::AngleAxisd(ego_yaw + M_PI / 6, Eigen::Vector3d::UnitZ());
    b.size_wlh = Eigen::Vector3d(1.9, 4.6, 1.7);
    b.velocity = Eigen::Vector2d(5 * std::cos(ego_yaw), 5 * std::sin(ego_yaw));  // 5 m/s along the ego heading
    const beslam_box3d c = cameraFromGlobal(b, BESLAM_CLASS_CAR, T_cam_global);
    // Camera frame: ahead is +z, left is -x; the centre is the geometric centre.
    const Eigen::Vector3d expected_cam = T_ego_cam.inverse() * Eigen::Vector3d(15, 2, 0.8);
    EXPECT_NEAR(c.center_cam[0], expected_cam.x(), 1e-9);
    EXPECT_NEAR(c.center_cam[2], expected_cam.z(), 1e-9);
    EXPECT_GT(c.center_cam[2], 13.0);
    EXPECT_LT(c.center_cam[0], -1.5);
    EXPECT_DOUBLE_EQ(c.size[0], 4.6);
    EXPECT_DOUBLE_EQ(c.size[1], 1.9);
    EXPECT_DOUBLE_EQ(c.size[2], 1.7);
    // KITTI ry: 0 = facing camera +x (right); heading 30 deg left of forward = ry -(90 + 30) deg... within the
    // small camera mount rotation.
    EXPECT_NEAR(c.yaw, -M_PI / 2 - M_PI / 6, 0.02);
    ASSERT_TRUE(c.flags & BESLAM_BOX_HAS_VELOCITY);
    EXPECT_NEAR(c.velocity_cam[2], 5.0, 0.05);  // forward
    EXPECT_NEAR(std::hypot(c.velocity_cam[0], c.velocity_cam[2]), 5.0, 0.05);
    // And back to global.
    const NuScenesBox back = globalFromCamera(c, T_cam_global);
    EXPECT_NEAR((back.translation - b.translation).norm(), 0.0, 1e-9);
    EXPECT_NEAR((back.size_wlh - b.size_wlh).norm(), 0.0, 1e-12);
    EXPECT_NEAR(back.rotation.angularDistance(b.rotation), 0.0, 0.01);  // the heading, projected
    EXPECT_NEAR((*back.velocity - *b.velocity).norm(), 0.0, 0.02);
  }
  // An exactly level camera (ego flat, extrinsic without mount error) round-trips exactly.
  const Eigen::Isometry3d level = poseFromTranslationQuaternion({1.7, 0, 1.5, 0.5, -0.5, 0.5, -0.5}, "level");
  const Eigen::Isometry3d T_cam_global = level.inverse() * egoPose(10, -4, 0.4).inverse();
  NuScenesBox b;
  b.translation = Eigen::Vector3d(30, 5, 1);
  b.rotation = Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitZ());
  const NuScenesBox back = globalFromCamera(cameraFromGlobal(b, BESLAM_CLASS_CAR, T_cam_global), T_cam_global);
  EXPECT_NEAR((back.translation - b.translation).norm(), 0.0, 1e-9);
  EXPECT_NEAR(back.rotation.angularDistance(b.rotation), 0.0, 1e-9);
  EXPECT_THROW(poseFromTranslationQuaternion({1, 2, 3}, "x"), std::invalid_argument);
  EXPECT_THROW(poseFromTranslationQuaternion({1, 2, 3, 0, 0, 0, 0}, "x"), std::invalid_argument);
}

TEST(NuScenesFramesFile, TextAndJsonForms) {
  Dir d;
  const NuScenesFrames text = readNuScenesFrames(d.write("tokens.txt", "# frame order\ntok_a\n\n  tok_b  \r\ntok_c\n"));
  EXPECT_EQ(text.tokens, (std::vector<std::string>{"tok_a", "tok_b", "tok_c"}));
  EXPECT_FALSE(text.T_global_ego[0]);
  const NuScenesFrames plain = readNuScenesFrames(d.write("tokens.json", R"(["a", "b"])"));
  EXPECT_EQ(plain.tokens.size(), 2u);
  const NuScenesFrames posed = readNuScenesFrames(
      d.write("frames.json", R"({"frames": [{"token": "a", "ego_translation": [1, 2, 0], "ego_rotation": [1, 0, 0, 0]},
                                    {"token": "b"}]})"));
  ASSERT_TRUE(posed.T_global_ego[0]);
  EXPECT_NEAR(posed.T_global_ego[0]->translation().y(), 2.0, 1e-12);
  EXPECT_FALSE(posed.T_global_ego[1]);
  for (const auto& [name, text_in, cause] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"two.txt", "tok_a\ntok_b tok_c\n", "two.txt:2: expected one sample token"},
           {"empty.txt", "# none\n", "no sample tokens"},
           {"syntax.json", "[\"a\",\n \"b\"\n", "syntax.json:3: JSON syntax error"},
           {"overflow.json", "[1e400]", "overflow.json: JSON error"},  // found by the nuscenes fuzz target
           {"object.json", R"({"x": 1})", "expected an array"},
           {"number.json", R"([1])", "frame 0: expected a token string"},
           {"half.json", R"([{"token": "a", "ego_translation": [1, 2, 0]}])", "go together"},
           {"zeroq.json", R"([{"token": "a", "ego_translation": [1, 2, 0], "ego_rotation": [0, 0, 0, 0]}])",
            "zero quaternion"}}) {
    try {
      readNuScenesFrames(d.write(name, text_in));
      ADD_FAILURE() << name << " accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(cause), std::string::npos) << name << ": " << e.what();
    }
  }
  EXPECT_THROW(readNuScenesFrames((d.path() / "absent.txt").string()), std::runtime_error);
}

TEST(NuScenesResults, ReadsFramesThroughTheTokenMap) {
  Dir d;
  NuScenesOptions o;
  o.frames.tokens = {"t0", "t1", "t2", "t3"};
  o.frames.T_global_ego = {egoPose(0, 0, 0), egoPose(5, 0, 0), std::nullopt, egoPose(15, 0, 0)};
  o.T_ego_cam = poseFromTranslationQuaternion({0, 0, 0, 0.5, -0.5, 0.5, -0.5}, "cam");
  json results = json::object();
  results["t0"] =
      json::array({box("t0", {20, 3, 1}, 0.0), box("t0", {-20, 0, 1}, 0.0), box("t0", {30, 0, 1}, 0, "barrier")});
  results["t1"] = json::array({box("t1", {25, 3, 1}, 0.0, "car", 0.2)});
  results["t2"] = json::array({box("t2", {25, 3, 1}, 0.0)});  // no ego pose for frame 2
  // t3 absent from the results
  o.results = d.write("results.json", json{{"meta", {{"use_camera", true}}}, {"results", results}}.dump(1));
  o.filter.min_depth = 0.0;  // the box behind the ego is dropped
  o.filter.min_score = 0.3;
  o.filter.classes = parseClassList("Car,Truck,Pedestrian,Cyclist");
  DetectionTable table;
  std::vector<char> covered;
  Report report;
  readNuScenes(o, table, covered, report);
  EXPECT_EQ(covered, (std::vector<char>{1, 1, 0, 0}));
  ASSERT_EQ(table.at(0).size(), 1u);
  EXPECT_NEAR(table.at(0)[0].center_cam[2], 20.0, 1e-9);
  EXPECT_NEAR(table.at(0)[0].center_cam[0], -3.0, 1e-9);
  EXPECT_NEAR(table.at(0)[0].center_cam[1], -1.0 + 0.3, 1e-9);  // 1 m up, ego 0.3 m above global z = 0
  EXPECT_NEAR(table.at(0)[0].yaw, -M_PI / 2, 1e-9);             // heading forward = camera +z
  EXPECT_TRUE(table.at(1).empty());                             // score 0.2 < 0.3
  EXPECT_EQ(report.rows, 4);                                    // frame 2 (no ego pose) is not read
  EXPECT_EQ(report.boxes, 1);
  EXPECT_EQ(report.filtered, 3);
  // Per-frame poses from a pose list override the token file's.
  o.ego_poses = {egoPose(10, 0, 0)};
  DetectionTable t2;
  readNuScenes(o, t2, covered, report);
  EXPECT_NEAR(t2.at(0)[0].center_cam[2], 10.0, 1e-9);
}

TEST(NuScenesResults, EveryMalformedBoxIsReported) {
  Dir d;
  const json good = box("t0", {20, 3, 1}, 0.0);
  auto with = [&](const std::string& key, const json& value) {
    json b = good;
    if (value.is_null())
      b.erase(key);
    else
      b[key] = value;
    return b;
  };
  const std::vector<std::pair<json, std::string>> cases = {
      {with("translation", json::array({1, 2})), "translation: expected an array of 3 numbers"},
      {with("translation", json::array({1, "x", 2})), "is not a number"},
      {with("size", json::array({1.9, 0, 1.7})), "size (w l h) must be positive"},
      {with("rotation", json::array({0, 0, 0, 0})), "zero quaternion"},
      {with("rotation", nullptr), "missing 'rotation'"},
      {with("velocity", json::array({1})), "velocity: expected [vx, vy]"},
      {with("detection_name", "spaceship"), "unknown detection_name 'spaceship'"},
      {with("detection_name", 3), "detection_name is not a string"},
      {with("detection_score", "high"), "detection_score is not a finite number"},
      {json::array({1, 2}), "expected a box object"},
  };
  for (const auto& [bad, cause] : cases) {
    NuScenesOptions o;
    o.frames.tokens = {"t0"};
    o.frames.T_global_ego = {egoPose(0, 0, 0)};
    o.results = d.write("bad.json", json{{"results", {{"t0", json::array({good, bad})}}}}.dump(1));
    DetectionTable table;
    std::vector<char> covered;
    Report report;
    try {
      readNuScenes(o, table, covered, report);
      ADD_FAILURE() << "accepted " << bad.dump();
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(o.results + ": sample t0, box 1: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(cause), std::string::npos) << e.what();
    }
    o.policy = Policy::skip;
    DetectionTable t2;
    Report r2;
    readNuScenes(o, t2, covered, r2);
    EXPECT_EQ(r2.skipped, 1) << cause;
    EXPECT_EQ(t2.at(0).size(), 1u) << cause;
  }
  // Unknown velocity written as null / NaN strings is not an error: the box has no velocity.
  NuScenesOptions o;
  o.frames.tokens = {"t0"};
  o.frames.T_global_ego = {egoPose(0, 0, 0)};
  o.results =
      d.write("nanvel.json",
              json{{"results", {{"t0", json::array({with("velocity", json::array({nullptr, nullptr}))})}}}}.dump());
  DetectionTable table;
  std::vector<char> covered;
  Report report;
  readNuScenes(o, table, covered, report);
  ASSERT_EQ(table.at(0).size(), 1u);
  EXPECT_FALSE(table.at(0)[0].flags & BESLAM_BOX_HAS_VELOCITY);
  // Whole-file problems.
  for (const auto& [text, cause] : std::vector<std::pair<std::string, std::string>>{
           {"{\"results\": {\n\"t0\": [\n}", "bad2.json:3: JSON syntax error"},
           {"{\"results\": {\"t0\": [{\"size\": [3.3E3333]}]}}", "bad2.json: JSON error"},
           {"[]", "expected a nuScenes results object"},
           {"{\"results\": {\"t0\": 5}}", "sample t0: expected a list of boxes"}}) {
    o.results = d.write("bad2.json", text);
    try {
      readNuScenes(o, table, covered, report);
      ADD_FAILURE() << "accepted " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(cause), std::string::npos) << e.what();
    }
  }
}
