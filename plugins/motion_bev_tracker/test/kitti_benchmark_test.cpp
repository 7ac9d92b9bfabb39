// The motion benchmark on real data (KITTI tracking with PointRCNN detections and ORB-SLAM3 ego poses),
// its figures asserted as floors; skipped when ../shared/data is absent. Also the benchmark's own
// handling of malformed inputs.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "kitti_motion_eval.hpp"

namespace fs = std::filesystem;

namespace {

std::string trackingRoot() { return std::string(BESLAM_SHARED_DATA) + "/kitti/tracking/training"; }

// Time floors only mean something in an optimised build without sanitizers.
#if defined(NDEBUG) && !defined(__SANITIZE_ADDRESS__)
constexpr bool kTimed = true;
#else
constexpr bool kTimed = false;
#endif

bool haveData(const std::string& seq) {
  const fs::path r = trackingRoot();
  return fs::exists(r / "det_pointrcnn" / "Car" / (seq + ".txt")) && fs::exists(r / "label_02" / (seq + ".txt")) &&
         fs::exists(r / "ego_poses_orbslam3" / (seq + ".txt"));
}

// The quality floors (F1, moving called static, parked called dynamic) and, in a timed build, the speed.
void expectFloors(const beslam::motion::EvalCounts& c) {
  EXPECT_GE(c.f1(), 0.95);
  EXPECT_LE(c.movingCalledStatic(), 0.01);
  EXPECT_LE(c.parkedCalledDynamic(), 0.03);
  if (kTimed) {
    EXPECT_LT(c.medianMs(), 1.0);
  }
}

}  // namespace

TEST(MotionBenchmark, Sequence0000MeetsTheFloors) {
  if (!haveData("0000")) GTEST_SKIP() << "shared KITTI tracking data not found under " << trackingRoot();
  beslam::motion::EvalOptions o;
  o.root = trackingRoot();
  const beslam::motion::EvalCounts c = beslam::motion::evaluateSequence(o, "0000");
  EXPECT_EQ(c.frames, 154);
  EXPECT_GE(c.moving, 100);  // enough of both kinds to mean something
  EXPECT_GE(c.parked, 200);
  expectFloors(c);
}

TEST(MotionBenchmark, AllSequencesMeetTheOverallFloors) {
  beslam::motion::EvalOptions o;
  o.root = trackingRoot();
  beslam::motion::EvalCounts all;
  for (const char* seq : {"0000", "0001", "0002", "0003", "0004", "0005", "0006", "0007", "0008", "0009", "0010"}) {
    if (!haveData(seq))
      GTEST_SKIP() << "shared KITTI tracking sequence " << seq << " not found under " << trackingRoot();
    all.add(beslam::motion::evaluateSequence(o, seq));
  }
  expectFloors(all);
}

TEST(MotionBenchmark, MalformedInputsNameTheFile) {
  const fs::path root = fs::temp_directory_path() / ("beslam_motion_bench_" + std::to_string(::getpid()));
  fs::create_directories(root / "det_pointrcnn" / "Car");
  fs::create_directories(root / "ego_poses_orbslam3");
  fs::create_directories(root / "label_02");
  std::ofstream(root / "det_pointrcnn" / "Car" / "0000.txt") << "0,2,1,1,50,50,5.0,1.5,1.6,4.0,1.0,1.6,10.0,0.0,0.0\n";
  std::ofstream(root / "label_02" / "0000.txt") << "0 0 Car 0 0 0.0 1 1 50 50 1.5 1.6 4.0 1.0 1.6 10.0 0.0\n";
  beslam::motion::EvalOptions o;
  o.root = root.string();
  // Malformed pose file: a short row.
  std::ofstream(root / "ego_poses_orbslam3" / "0000.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0\n";
  try {
    beslam::motion::evaluateSequence(o, "0000");
    FAIL() << "accepted a malformed pose file";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("0000.txt:2"), std::string::npos) << e.what();
  }
  // Good poses, then a malformed detection row.
  std::ofstream(root / "ego_poses_orbslam3" / "0000.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  EXPECT_NO_THROW(beslam::motion::evaluateSequence(o, "0000"));
  std::ofstream(root / "det_pointrcnn" / "Car" / "0000.txt") << "0,2,1,1,50,50,5.0,1.5,1.6,nan,1.0,1.6,10.0,0.0,0.0\n";
  try {
    beslam::motion::evaluateSequence(o, "0000");
    FAIL() << "accepted a NaN detection";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("0000.txt:1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(beslam::motion::evaluateSequence(o, "0001"), std::exception);  // missing files
  fs::remove_all(root);
}
