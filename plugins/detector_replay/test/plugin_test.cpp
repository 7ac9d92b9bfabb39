// detector_replay through the host's registry: each format from files the test writes, the real shared
// PointRCNN detections, configuration errors, and the stop / skip and missing-frame policies.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "beslam/formats/error.hpp"
#include "beslam/test/plugin_harness.hpp"
#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;
using beslam::test::PluginHarness;

namespace {

const std::string kLib = std::string(PLUGIN_DIR) + "/detector_replay.so";

using Dir = beslam::test::TempDir;

std::vector<beslam_box3d> detect(beslam::registry::DetectorInstance& d, int64_t frame) {
  return d.detect(PluginHarness::frame(frame, 0.1 * static_cast<double>(frame)));
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(DetectorReplayPlugin, Ab3dmotFolderLayout) {
  PluginHarness h(kLib);
  Dir d;
  d.write("det/Car/0003.txt",
          "0,2,1,1,50,50,5.0,1.5,1.6,4.0,1.0,1.6,10.0,0.0,0.0\n2,2,1,1,50,50,-3.0,1.5,1.6,4.0,1.0,1.6,12.0,0.0,0.0\n");
  d.write("det/Pedestrian/0003.txt", "2,1,1,1,50,50,2.0,1.7,0.6,0.8,-2.0,1.6,8.0,0.0,0.0\n");
  const auto& config = h.config(
      "detector_replay",
      {{"format", "ab3dmot"}, {"path", (d.path() / "det").string()}, {"sequence", "0003"}, {"min_score", "0.5"}});
  beslam::registry::DetectorInstance det(h.plugin("detector_replay"), h.info(config), h.log);
  EXPECT_EQ(detect(det, 0).size(), 1u);
  EXPECT_TRUE(detect(det, 1).empty());  // a frame without detections inside the covered range
  const auto f2 = detect(det, 2);       // the car's logit -3 is below sigmoid 0.5
  ASSERT_EQ(f2.size(), 1u);
  EXPECT_EQ(f2[0].class_id, BESLAM_CLASS_PEDESTRIAN);
  EXPECT_NEAR(f2[0].center_cam[1], 1.6 - 0.85, 1e-12);
  const std::string e = errorOf([&] { detect(det, 3); });
  EXPECT_NE(e.find("frame 3"), std::string::npos) << e;
  EXPECT_NE(e.find("past the last frame (2)"), std::string::npos) << e;

  const auto& empty = h.config("detector_replay", {{"format", "ab3dmot"},
                                                   {"path", (d.path() / "det").string()},
                                                   {"sequence", "0003"},
                                                   {"on_missing_frame", "empty"},
                                                   {"classes", "Car"}});
  beslam::registry::DetectorInstance lenient(h.plugin("detector_replay"), h.info(empty), h.log);
  EXPECT_TRUE(detect(lenient, 3).empty());
  EXPECT_EQ(detect(lenient, 2).size(), 1u);  // only the car (classes: Car), score filter off
  EXPECT_EQ(detect(lenient, 2)[0].class_id, BESLAM_CLASS_CAR);
}

TEST(DetectorReplayPlugin, MalformedRowsStopOrAreSkipped) {
  PluginHarness h(kLib);
  Dir d;
  const std::string file = d.write("rows.txt",
                                   "0,2,1,1,50,50,5.0,1.5,1.6,4.0,1.0,1.6,10.0,0.0,0.0\n"
                                   "1,9,1,1,50,50,5.0,1.5,1.6,4.0,1.0,1.6,10.0,0.0,0.0\n"
                                   "2,2,1,1,50,50,5.0,1.5,1.6,4.0,1.0,1.6,10.0,0.0,0.0\n");
  const auto& stop = h.config("detector_replay", {{"format", "ab3dmot"}, {"path", file}});
  const std::string e =
      errorOf([&] { beslam::registry::DetectorInstance x(h.plugin("detector_replay"), h.info(stop), h.log); });
  EXPECT_NE(e.find(file + ":2: unknown class id 9"), std::string::npos) << e;
  const auto& skip = h.config("detector_replay", {{"format", "ab3dmot"}, {"path", file}, {"on_error", "skip"}});
  beslam::registry::DetectorInstance det(h.plugin("detector_replay"), h.info(skip), h.log);
  EXPECT_EQ(detect(det, 0).size(), 1u);
  EXPECT_TRUE(detect(det, 1).empty());
  EXPECT_EQ(detect(det, 2).size(), 1u);
}

TEST(DetectorReplayPlugin, ConfigurationErrors) {
  PluginHarness h(kLib);
  Dir d;
  d.write("det/Car/0000.txt", "0,2,1,1,50,50,5.0,1.5,1.6,4.0,1.0,1.6,10.0,0.0,0.0\n");
  auto create = [&](const std::map<std::string, std::string>& s) {
    return errorOf([&] {
      beslam::registry::DetectorInstance x(h.plugin("detector_replay"), h.info(h.config("detector_replay", s)), h.log);
    });
  };
  EXPECT_NE(create({{"format", "ab3dmot"}, {"path", (d.path() / "det").string()}}).find("sequence"), std::string::npos);
  EXPECT_NE(create({{"format", "ab3dmot"}, {"path", (d.path() / "det").string()}, {"sequence", "0007"}})
                .find("no detection file"),
            std::string::npos);
  EXPECT_NE(
      create(
          {{"format", "ab3dmot"}, {"path", (d.path() / "det").string()}, {"sequence", "0000"}, {"classes", "Car,Bus"}})
          .find("unknown class 'Bus'"),
      std::string::npos);
  EXPECT_NE(create({{"format", "nuscenes"}, {"path", (d.path() / "r.json").string()}}).find("sample_tokens"),
            std::string::npos);
  EXPECT_NE(create({{"format", "kitti_tracking"}, {"path", (d.path() / "absent.txt").string()}}).find("absent.txt"),
            std::string::npos);
}

TEST(DetectorReplayPlugin, KittiTrackingAndObjectFolders) {
  PluginHarness h(kLib);
  Dir d;
  d.write("label_02/0001.txt",
          "0 0 Car 0 0 0.1 1 1 9 9 1.5 1.6 4.0 1 1.6 10 0\n1 0 Car 0 0 0.1 1 1 9 9 1.5 1.6 4.0 1 1.6 11 0\n");
  const auto& tracking =
      h.config("detector_replay",
               {{"format", "kitti_tracking"}, {"path", (d.path() / "label_02").string()}, {"sequence", "0001"}});
  beslam::registry::DetectorInstance t(h.plugin("detector_replay"), h.info(tracking), h.log);
  EXPECT_NEAR(detect(t, 1)[0].center_cam[2], 11.0, 1e-12);
  d.write("label_2/000000.txt", "Car 0.00 0 1.74 741.18 168.83 792.25 208.43 1.70 1.63 4.08 7.24 1.55 33.20 1.95\n");
  const auto& object =
      h.config("detector_replay", {{"format", "kitti_object"}, {"path", (d.path() / "label_2").string()}});
  beslam::registry::DetectorInstance o(h.plugin("detector_replay"), h.info(object), h.log);
  EXPECT_EQ(detect(o, 0).size(), 1u);
  EXPECT_NE(errorOf([&] { detect(o, 1); }).find("000001.txt"), std::string::npos);
}

TEST(DetectorReplayPlugin, NuScenesWithPoseFileAndExtrinsic) {
  PluginHarness h(kLib);
  Dir d;
  using json = nlohmann::json;
  auto car = [](double x, double y) {
    return json{{"sample_token", "s"},      {"translation", {x, y, 1.0}}, {"size", {1.9, 4.6, 1.7}},
                {"rotation", {1, 0, 0, 0}}, {"velocity", {2.0, 0.0}},     {"detection_name", "car"},
                {"detection_score", 0.6}};
  };
  const std::string results =
      d.write("results.json", json{{"results", {{"tok0", {car(20, 1)}}, {"tok1", {car(20, 1)}}}}}.dump());
  const std::string tokens = d.write("tokens.txt", "tok0\ntok1\ntok2\n");
  // Ego at x = 0 then x = 5 (global), heading +x, 0.5 m up; KITTI pose rows (3x4 of T_global_ego).
  const std::string poses =
      d.write("ego.txt", "1 0 0 0 0 1 0 0 0 0 1 0.5\n1 0 0 5 0 1 0 0 0 0 1 0.5\n1 0 0 10 0 1 0 0 0 0 1 0.5\n");
  const std::map<std::string, std::string> base = {{"format", "nuscenes"},
                                                   {"path", results},
                                                   {"sample_tokens", tokens},
                                                   {"ego_poses", poses},
                                                   {"camera_extrinsic", "[1.5, 0, 1.0, 0.5, -0.5, 0.5, -0.5]"}};
  beslam::registry::DetectorInstance det(h.plugin("detector_replay"), h.info(h.config("detector_replay", base)), h.log);
  const auto f0 = detect(det, 0);
  ASSERT_EQ(f0.size(), 1u);
  EXPECT_NEAR(f0[0].center_cam[2], 20 - 1.5, 1e-9);            // ahead of a camera 1.5 m forward of the ego
  EXPECT_NEAR(f0[0].center_cam[0], -1.0, 1e-9);                // 1 m left
  EXPECT_NEAR(f0[0].center_cam[1], -(1.0 - 0.5 - 1.0), 1e-9);  // 1 m up in global, camera 1.5 m up
  EXPECT_NEAR(f0[0].velocity_cam[2], 2.0, 1e-9);
  EXPECT_NEAR(detect(det, 1)[0].center_cam[2], 20 - 5 - 1.5, 1e-9);
  const std::string e = errorOf([&] { detect(det, 2); });  // tok2 has no results
  EXPECT_NE(e.find("frame 2: no results"), std::string::npos) << e;
  EXPECT_NE(errorOf([&] { detect(det, 3); }).find("no sample token"), std::string::npos);
  auto bad_extrinsic = base;
  bad_extrinsic["camera_extrinsic"] = "[1, 2, 3]";
  EXPECT_NE(errorOf([&] {
              beslam::registry::DetectorInstance x(h.plugin("detector_replay"),
                                                   h.info(h.config("detector_replay", bad_extrinsic)), h.log);
            }).find("camera_extrinsic"),
            std::string::npos);
}

TEST(DetectorReplayPlugin, RealPointRcnnSequence) {
  const fs::path root = fs::path(BESLAM_SHARED_DATA) / "kitti/tracking/training/det_pointrcnn";
  if (!fs::exists(root / "Car" / "0000.txt")) GTEST_SKIP() << "shared data not found: " << root;
  PluginHarness h(kLib);
  const auto& config = h.config(
      "detector_replay", {{"format", "ab3dmot"}, {"path", root.string()}, {"sequence", "0000"}, {"min_score", "0.8"}});
  beslam::registry::DetectorInstance det(h.plugin("detector_replay"), h.info(config), h.log);
  size_t total = 0;
  for (int64_t f = 0; f < 154; ++f) {
    const auto boxes = detect(det, f);
    for (const auto& b : boxes) EXPECT_GE(b.score, 0.8f);
    total += boxes.size();
  }
  EXPECT_GT(total, 800u);
  EXPECT_NE(errorOf([&] { detect(det, 154); }).find("past the last frame (153)"), std::string::npos);
}
