// The label oracle: truth reading (KITTI and synthetic layouts, motion flags), seeded faults (noise
// statistics, misses, false positives), determinism, track-id pass-through, errors, and the plugin.
#include "beslam/detector_oracle/oracle.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "beslam/test/plugin_harness.hpp"
#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace beslam::detector_oracle;
using beslam::test::PluginHarness;

namespace {

using Dir = beslam::test::TempDir;

// 200 frames, two cars (track 1 parked at 20 m, track 2 at 40 m) and a DontCare row.
std::string labels() {
  std::string s;
  for (int f = 0; f < 200; ++f) {
    s += std::to_string(f) + " 1 Car 0 0 -1.5 100 150 200 250 1.5 1.6 4.0 -3.0 1.7 20.0 1.57\n";
    s += std::to_string(f) + " 2 Van 0 1 -1.5 300 150 340 200 2.0 1.8 4.5 5.0 1.7 40.0 0.0\n";
    s += std::to_string(f) + " -1 DontCare -1 -1 -10 1 1 5 5 -1000 -1000 -1000 -10 -1 -1 -1\n";
  }
  return s;
}

}  // namespace

TEST(Random, DeterministicAndDistributed) {
  Random a(Random::mix(42, 7)), b(Random::mix(42, 7)), c(Random::mix(42, 8));
  EXPECT_EQ(a.uniform(), b.uniform());
  EXPECT_NE(Random(Random::mix(42, 7)).uniform(), c.uniform());
  // The sequence itself is fixed by the standard (mt19937_64) and our transforms: pin one value.
  Random pinned(12345);
  EXPECT_NEAR(pinned.uniform(), 0.357629722888, 1e-12);
  Random r(1);
  double sum = 0, sq = 0, pois = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = r.normal();
    sum += x, sq += x * x;
    pois += r.poisson(2.5);
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sq / n, 1.0, 0.01);
  EXPECT_NEAR(pois / n, 2.5, 0.02);
  EXPECT_EQ(r.poisson(0.0), 0);
}

TEST(LabelOracle, ReadsTruthWithGeometryAndMotion) {
  Dir d;
  const std::string file = d.write("label_02/0000.txt", labels());
  const std::string motion = d.write("objects_motion.txt", "# frame track_id moving speed\n0 1 0 0.0\n0 2 1 7.5\n");
  const auto truth = readTruth(file, motion);
  ASSERT_EQ(truth.size(), 200u);
  ASSERT_EQ(truth[0].size(), 2u);  // DontCare skipped
  const beslam_box3d& car = truth[0][0].box;
  EXPECT_EQ(car.class_id, BESLAM_CLASS_CAR);
  EXPECT_EQ(car.track_id, 1);
  EXPECT_DOUBLE_EQ(car.center_cam[1], 1.7 - 0.75);
  EXPECT_DOUBLE_EQ(car.size[0], 4.0);
  EXPECT_EQ(car.motion_state, BESLAM_MOTION_STATIC);
  EXPECT_EQ(truth[0][1].box.motion_state, BESLAM_MOTION_DYNAMIC);
  EXPECT_EQ(truth[1][0].box.motion_state, BESLAM_MOTION_UNKNOWN);  // no motion row
  for (const auto& [name, text, cause] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"bad_class.txt", "0 1 Bus 0 0 -1.5 1 1 2 2 1.5 1.6 4.0 -3.0 1.7 20.0 1.57\n",
            "bad_class.txt:1: unknown class 'Bus'"},
           {"bad_number.txt", "0 1 Car 0 0 -1.5 1 1 2 2 1.5 1.6 4.0 -3.0 nan 20.0 1.57\n", "bad_number.txt:1"},
           {"bad_size.txt", "0 1 Car 0 0 -1.5 1 1 2 2 1.5 0 4.0 -3.0 1.7 20.0 1.57\n", "bad_size.txt:1: non-positive"},
           {"empty.txt", "\n", "no labels"}}) {
    try {
      readTruth(d.write(name, text));
      ADD_FAILURE() << name;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(cause), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(readTruth(file, d.write("m.txt", "0 1 2 0.0\n")), std::runtime_error);  // moving must be 0/1
  EXPECT_THROW(readTruth((d.path() / "absent.txt").string()), std::runtime_error);
}

TEST(LabelOracle, PerfectByDefault) {
  Dir d;
  LabelOracle oracle(readTruth(d.write("l.txt", labels())), OracleOptions{});
  const auto boxes = oracle.detect(5);
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_DOUBLE_EQ(boxes[0].center_cam[2], 20.0);
  EXPECT_EQ(boxes[0].track_id, -1);  // ids are not passed on unless asked
  EXPECT_GE(boxes[0].score, 0.6f);
  EXPECT_THROW(oracle.detect(200), std::out_of_range);
  OracleOptions ids;
  ids.pass_track_ids = true;
  EXPECT_EQ(LabelOracle(readTruth(d.write("l2.txt", labels())), ids).detect(5)[1].track_id, 2);
}

TEST(LabelOracle, NoiseMissesAndFalsePositivesHaveTheConfiguredStatistics) {
  Dir d;
  OracleOptions o;
  o.position_noise = 0.2;
  o.depth_noise_per_m = 0.01;  // 0.2 m along the ray at 20 m, 0.4 m at 40 m
  o.size_noise = 0.05;
  o.yaw_noise = 0.1;
  o.miss_rate = 0.25;
  o.seed = 99;
  o.classes = {BESLAM_CLASS_CAR, BESLAM_CLASS_VAN};
  LabelOracle oracle(readTruth(d.write("l.txt", labels())), o);
  int near = 0, far = 0, fps = 0;
  double near_z2 = 0, far_z2 = 0, x2 = 0, yaw2 = 0, len2 = 0;
  for (int f = 0; f < 200; ++f) {
    for (const beslam_box3d& b : oracle.detect(f)) {
      if (std::abs(b.center_cam[2] - 20) < 3 && std::abs(b.center_cam[0] + 3) < 1.5) {
        ++near;
        near_z2 += std::pow(b.center_cam[2] - 20, 2);
        yaw2 += std::pow(b.yaw - 1.57, 2);
        len2 += std::pow(b.size[0] / 4.0 - 1, 2);
      } else if (std::abs(b.center_cam[2] - 40) < 3 && std::abs(b.center_cam[0] - 5) < 1.5) {
        ++far;
        far_z2 += std::pow(b.center_cam[2] - 40, 2);
        x2 += std::pow(b.center_cam[0] - 5, 2);
      } else {
        ++fps;
      }
    }
  }
  EXPECT_NEAR(near / 200.0, 0.75, 0.08);  // miss rate
  EXPECT_NEAR(far / 200.0, 0.75, 0.08);
  EXPECT_EQ(fps, 0);
  EXPECT_NEAR(std::sqrt(near_z2 / near), std::hypot(0.2, 0.2), 0.06);
  EXPECT_NEAR(std::sqrt(far_z2 / far), std::hypot(0.2, 0.4), 0.08);
  EXPECT_NEAR(std::sqrt(x2 / far), 0.2, 0.05);  // the ray is almost along z at 40 m ahead
  EXPECT_NEAR(std::sqrt(yaw2 / near), 0.1, 0.03);
  EXPECT_NEAR(std::sqrt(len2 / near), 0.05, 0.015);
  // False positives only: a Poisson count per frame on top of the (perfect) true boxes.
  OracleOptions f;
  f.false_positives = 1.5;
  f.seed = 4;
  LabelOracle with_fp(readTruth(d.write("l3.txt", labels())), f);
  int total = 0;
  for (int k = 0; k < 200; ++k) {
    const auto boxes = with_fp.detect(k);
    total += static_cast<int>(boxes.size()) - 2;
    for (size_t i = 2; i < boxes.size(); ++i) {
      EXPECT_LE(boxes[i].score, 0.9f);
      EXPECT_EQ(boxes[i].track_id, -1);
      EXPECT_GT(boxes[i].center_cam[2], 2.9);
    }
  }
  EXPECT_NEAR(total / 200.0, 1.5, 0.25);
}

TEST(LabelOracle, AFramesBoxesDependOnSeedAndFrameOnly) {
  Dir d;
  OracleOptions o;
  o.position_noise = 0.3;
  o.miss_rate = 0.3;
  o.false_positives = 1;
  o.seed = 5;
  const auto truth = readTruth(d.write("l.txt", labels()));
  LabelOracle a(truth, o), b(truth, o);
  for (int f : {0, 1, 2, 3}) a.detect(f);  // a different call history
  const auto x = a.detect(17), y = b.detect(17);
  ASSERT_EQ(x.size(), y.size());
  for (size_t i = 0; i < x.size(); ++i) {
    EXPECT_EQ(x[i].center_cam[0], y[i].center_cam[0]);
    EXPECT_EQ(x[i].center_cam[2], y[i].center_cam[2]);
    EXPECT_EQ(x[i].score, y[i].score);
  }
  o.seed = 6;
  const auto z = LabelOracle(truth, o).detect(17);
  EXPECT_TRUE(z.size() != x.size() || z[0].center_cam[2] != x[0].center_cam[2]);
  OracleOptions bad;
  bad.miss_rate = 1.5;
  EXPECT_THROW(LabelOracle(truth, bad), std::invalid_argument);
}

TEST(DetectorOraclePlugin, ThroughTheRegistry) {
  PluginHarness h(std::string(PLUGIN_DIR) + "/detector_oracle.so");
  Dir d;
  d.write("label_02/0004.txt", labels());
  const auto& config = h.config("detector_oracle", {{"labels", (d.path() / "label_02").string()},
                                                    {"sequence", "0004"},
                                                    {"position_noise", "0.1"},
                                                    {"seed", "3"},
                                                    {"pass_track_ids", "true"}});
  beslam::registry::DetectorInstance det(h.plugin("detector_oracle"), h.info(config), h.log);
  const auto boxes = det.detect(PluginHarness::frame(3, 0.3));
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_EQ(boxes[0].track_id, 1);
  EXPECT_NEAR(boxes[0].center_cam[2], 20.0, 0.6);
  try {
    det.detect(PluginHarness::frame(200, 20.0));
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("past the last labelled frame"), std::string::npos) << e.what();
  }
  auto missing = h.config("detector_oracle", {{"labels", (d.path() / "label_02").string()}});
  EXPECT_THROW(beslam::registry::DetectorInstance(h.plugin("detector_oracle"), h.info(missing), h.log), std::exception);
  // Without `labels`, the file is found beside the frame's image (KITTI tracking and beslam synth layouts).
  const auto& automatic = h.config("detector_oracle", {});
  beslam::registry::DetectorInstance tracking(h.plugin("detector_oracle"), h.info(automatic), h.log);
  beslam_frame f = PluginHarness::frame(0, 0.0);
  const std::string image = (d.path() / "image_02" / "0004" / "000000.png").string();
  f.image_path = image.c_str();
  EXPECT_EQ(tracking.detect(f).size(), 2u);
  d.write("synth/sequences/00/label_02/00.txt", labels());
  beslam::registry::DetectorInstance synth(h.plugin("detector_oracle"), h.info(automatic), h.log);
  const std::string synth_image = (d.path() / "synth/sequences/00/image_0/000000.png").string();
  f.image_path = synth_image.c_str();
  EXPECT_EQ(synth.detect(f).size(), 2u);
  beslam::registry::DetectorInstance nowhere(h.plugin("detector_oracle"), h.info(automatic), h.log);
  const std::string lost = (d.path() / "x/y/000000.png").string();
  f.image_path = lost.c_str();
  EXPECT_THROW(nowhere.detect(f), std::exception);
}

TEST(DetectorOraclePlugin, SharedKittiTrackingLabels) {
  const fs::path labels = fs::path(BESLAM_SHARED_DATA) / "kitti/tracking/training/label_02";
  if (!fs::exists(labels / "0000.txt")) GTEST_SKIP() << "shared data not found: " << labels;
  PluginHarness h(std::string(PLUGIN_DIR) + "/detector_oracle.so");
  const auto& config =
      h.config("detector_oracle", {{"labels", labels.string()}, {"sequence", "0000"}, {"classes", "Car,Van"}});
  beslam::registry::DetectorInstance det(h.plugin("detector_oracle"), h.info(config), h.log);
  size_t n = 0;
  for (int64_t f = 0; f < 154; ++f) n += det.detect(PluginHarness::frame(f, 0.1 * f)).size();
  EXPECT_GT(n, 400u);
}
