// The motion-state scorer on a hand-made sequence: two frames, one parked car, one moving car.
#include "beslam/motion_score/motion_score.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "beslam/common/error.hpp"

namespace fs = std::filesystem;
using beslam::motion_score::Counts;
using beslam::motion_score::Options;
using beslam::motion_score::score;

namespace {

// A tracking row: frame id type trunc occ alpha x1 y1 x2 y2 h w l x y z ry [score]
std::string row(int frame, int id, double x, double z, const char* type = "Car") {
  std::ostringstream s;
  s << frame << ' ' << id << ' ' << type << " 0 0 0 100 100 200 200 1.5 1.6 3.9 " << x << " 1.65 " << z << " 0";
  return s.str();
}

class MotionEvalTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("beslam_motion_score_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    write("labels.txt",
          row(0, 1, 3, 10) + "\n" + row(0, 2, -3, 40) + "\n" + row(1, 1, 3, 9) + "\n" + row(1, 2, -3, 39) + "\n");
    write("motion.txt", "# frame track moving speed\n0 1 0 0\n0 2 1 8\n1 1 0 0\n1 2 1 8\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream((dir_ / name).string()) << text;
    return (dir_ / name).string();
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(MotionEvalTest, CountsEachCaseAgainstTheTruth) {
  // Frame 0: parked called static, moving called dynamic. Frame 1: parked called dynamic, moving called static.
  // A detection 5 m from any label is unmatched; a pedestrian is not a car.
  write("objects.txt", row(0, 7, 3.2, 10.1) + " 0.9 static\n" + row(0, 8, -3, 40.5) + " 0.9 dynamic\n" +
                           row(1, 7, 3, 9) + " 0.9 dynamic\n" + row(1, 8, -3, 39) + " 0.9 static\n" +
                           row(1, 9, 10, 20) + " 0.9 unknown\n" + row(1, 10, 3, 9, "Pedestrian") + " 0.9 unknown\n");
  const Counts c = score(path("objects.txt"), path("labels.txt"), path("motion.txt"), Options{});
  EXPECT_EQ(c.detections, 5);
  EXPECT_EQ(c.matched, 4);
  EXPECT_EQ(c.tp, 1);
  EXPECT_EQ(c.fp, 1);
  EXPECT_EQ(c.fn, 1);
  EXPECT_EQ(c.moving_static, 1);
  EXPECT_EQ(c.standing_dynamic, 1);
  EXPECT_EQ(c.standing_near, 2);
  EXPECT_EQ(c.standing_near_static, 1);
  EXPECT_DOUBLE_EQ(c.f1(), 0.5);
}

TEST_F(MotionEvalTest, RangeLimitsWhatIsScored) {
  write("objects.txt", row(0, 7, 3, 10) + " 0.9 static\n" + row(0, 8, -3, 40) + " 0.9 static\n");
  Options o;
  o.max_range = 30;
  const Counts c = score(path("objects.txt"), path("labels.txt"), path("motion.txt"), o);
  EXPECT_EQ(c.matched, 1);
  EXPECT_EQ(c.moving, 0);
  EXPECT_EQ(c.standing, 1);
}

TEST_F(MotionEvalTest, BadInputNamesTheFile) {
  write("objects.txt", row(0, 7, 3, 10) + " 0.9 parked\n");
  try {
    score(path("objects.txt"), path("labels.txt"), path("motion.txt"), Options{});
    FAIL() << "no error";
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("objects.txt"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("parked"), std::string::npos) << e.what();
  }
  EXPECT_THROW(score(path("missing.txt"), path("labels.txt"), path("motion.txt"), Options{}), beslam::Error);
  // A matched label with no truth row is an error naming the motion file.
  write("objects.txt", row(0, 7, 3, 10) + " 0.9 static\n");
  write("motion.txt", "0 2 1 8\n");
  try {
    score(path("objects.txt"), path("labels.txt"), path("motion.txt"), Options{});
    FAIL() << "no error";
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("motion.txt"), std::string::npos) << e.what();
  }
}

TEST_F(MotionEvalTest, CommandReportsAndRejectsBadUsage) {
  write("objects.txt", row(0, 7, 3, 10) + " 0.9 static\n");
  std::ostringstream out, err;
  EXPECT_EQ(beslam::motion_score::runCommand({"--objects", path("objects.txt"), "--labels", path("labels.txt"),
                                              "--motion", path("motion.txt"), "--json", path("m.json")},
                                             out, err),
            0)
      << err.str();
  EXPECT_NE(out.str().find("standing within 30"), std::string::npos) << out.str();
  EXPECT_TRUE(fs::exists(path("m.json")));
  EXPECT_EQ(beslam::motion_score::runCommand({"--max-range", "x"}, out, err), 2);
  EXPECT_EQ(beslam::motion_score::runCommand({"--run", path("nothing")}, out, err), 1);
}

}  // namespace
