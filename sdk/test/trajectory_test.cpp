#include "beslam/formats/trajectory.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "beslam/formats/error.hpp"
#include "beslam/test/scratch_dir.hpp"

namespace fs = std::filesystem;
using beslam::formats::Trajectory;
namespace traj = beslam::formats;

namespace {

class TrajectoryFiles : public beslam::test::ScratchDir {
 protected:
  // Expects `fn` to throw beslam::Error whose message starts with "path:line:" (or "path:" when line 0)
  // and contains `cause`.
  template <typename Fn>
  static void expectError(Fn&& fn, const std::string& path, int line, const std::string& cause) {
    try {
      fn();
      FAIL() << "expected beslam::Error for " << path;
    } catch (const beslam::Error& e) {
      const std::string message = e.what();
      const std::string prefix = line > 0 ? path + ":" + std::to_string(line) + ":" : path + ":";
      EXPECT_EQ(message.rfind(prefix, 0), 0u) << message;
      EXPECT_NE(message.find(cause), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << "one line only: " << message;
    }
  }
  // `trajectory` written to the scratch file `name` by write() and read back by read().
  template <typename Write, typename Read>
  Trajectory roundTrip(Write write, Read read, const std::string& name, const Trajectory& trajectory) {
    write(path(name), trajectory);
    return read(path(name));
  }
  // Writes `text` to the scratch file `name` and expects read(file) to fail so (see expectError).
  template <typename Read>
  void expectReadError(Read read, const std::string& name, const std::string& text, int line,
                       const std::string& cause) {
    const std::string file = write(name, text);
    expectError([&] { read(file); }, file, line, cause);
  }
};

const auto readTum = [](const std::string& file) { traj::readTum(file); };
const auto readKitti = [](const std::string& file) { traj::readKitti(file); };

Trajectory makeTrajectory(int n) {
  Trajectory trajectory;
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
    T_world_cam.linear() = (Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.1 * std::sin(i), Eigen::Vector3d::UnitX()))
                               .toRotationMatrix();
    T_world_cam.translation() = Eigen::Vector3d(std::cos(0.1 * i) * 3.1, 0.123456789 * i, -1e-7 * i);
    trajectory.push_back(1305031098.6659 + 0.0333333 * i, T_world_cam);
  }
  return trajectory;
}

}  // namespace

TEST_F(TrajectoryFiles, KittiRoundTripIsExact) {
  const Trajectory original = makeTrajectory(20);
  const Trajectory loaded = roundTrip(traj::writeKitti, traj::readKitti, "a.txt", original);
  ASSERT_EQ(loaded.size(), original.size());
  for (std::size_t i = 0; i < loaded.size(); ++i) {
    EXPECT_TRUE(loaded.poses[i].matrix() == original.poses[i].matrix()) << "pose " << i;
    EXPECT_EQ(loaded.stamps[i], static_cast<double>(i));
  }
}

TEST_F(TrajectoryFiles, TumRoundTripKeepsStampsAndPoses) {
  const Trajectory original = makeTrajectory(20);
  const Trajectory loaded = roundTrip(traj::writeTum, traj::readTum, "a.tum", original);
  ASSERT_EQ(loaded.size(), original.size());
  for (std::size_t i = 0; i < loaded.size(); ++i) {
    EXPECT_EQ(loaded.stamps[i], original.stamps[i]);
    EXPECT_TRUE(loaded.poses[i].translation() == original.poses[i].translation());
    EXPECT_TRUE(loaded.poses[i].linear().isApprox(original.poses[i].linear(), 1e-14));
  }
  EXPECT_EQ(traj::read(path("a.tum"), "tum").size(), 20u);
  EXPECT_EQ(traj::detectFormat(path("a.tum")), "tum");
}

TEST_F(TrajectoryFiles, TumNormalisesQuaternionsAndSkipsCommentsAndBlankLines) {
  const std::string file = write("q.tum",
                                 "# timestamp tx ty tz qx qy qz qw\r\n"
                                 "\n"
                                 "   \t\n"
                                 "1.5 1 2 3 0 0 0 2\r\n"
                                 "  # indented comment\n"
                                 "2.5,4,5,6,0,0,1,1\n"
                                 "+3.5 -1e-3 0 0 0 0 0 1");  // no final newline
  const Trajectory t = traj::readTum(file);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t.stamps[0], 1.5);
  EXPECT_EQ(t.stamps[2], 3.5);
  EXPECT_TRUE(t.poses[0].linear().isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  EXPECT_EQ(t.poses[0].translation(), Eigen::Vector3d(1, 2, 3));
  const Eigen::Matrix3d Rz90 = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(t.poses[1].linear().isApprox(Rz90, 1e-15));
  EXPECT_NEAR((t.poses[1].linear().transpose() * t.poses[1].linear() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-15);
  EXPECT_EQ(t.poses[2].translation().x(), -1e-3);
}

TEST_F(TrajectoryFiles, KittiKeepsRotationAsWritten) {
  // Printing-precision rotations (as ORB-SLAM writes them) are accepted and not re-orthonormalised.
  const std::string file = write("k.txt", "1 0 0 5 0 0.999999940 0 6 0 0 0.999999940 7\n");
  const Trajectory t = traj::readKitti(file);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t.poses[0].matrix()(1, 1), 0.999999940);
  EXPECT_EQ(t.poses[0].translation(), Eigen::Vector3d(5, 6, 7));
  EXPECT_EQ(t.poses[0].matrix().row(3), Eigen::RowVector4d(0, 0, 0, 1));
  EXPECT_EQ(traj::detectFormat(file), "kitti");
}

TEST_F(TrajectoryFiles, WrongColumnCountNamesFileAndLine) {
  const std::string kitti = write("k.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n\n1 0 0 0 0 1 0 0 0 0 1\n");
  expectError([&] { traj::readKitti(kitti); }, kitti, 3, "expected 12 numbers per row");
  expectReadError(readTum, "t.tum", "# header\n0 1 2 3 0 0 0 1 9\n", 2, "expected 8 numbers per row");
  expectError([&] { traj::readTum(kitti); }, kitti, 1, "found 12");
}

TEST_F(TrajectoryFiles, NonFiniteAndNonNumericValuesNameFileAndLine) {
  expectReadError(readTum, "nan.tum", "0 1 2 3 0 0 0 1\n1 nan 2 3 0 0 0 1\n", 2, "non-finite value 'nan'");
  expectReadError(readKitti, "inf.txt", "1 0 0 0 0 1 0 0 0 0 1 -inf\n", 1, "column 12: non-finite");
  expectReadError(readTum, "huge.tum", "1e999 1 2 3 0 0 0 1\n", 1, "non-finite");
  expectReadError(readTum, "word.tum", "0 1 2 3 0 0 0 1\n\n1 1 2 3x 0 0 0 1\n", 3, "column 4: '3x' is not a number");
}

TEST_F(TrajectoryFiles, RejectsZeroQuaternionAndNonRotation) {
  expectReadError(readTum, "z.tum", "0 1 2 3 0 0 0 0\n", 1, "quaternion has zero length");
  expectReadError(readKitti, "r.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 1 0 0 0 0 1 0\n", 2, "not a rotation matrix");
  expectReadError(readKitti, "m.txt", "1 0 0 0 0 1 0 0 0 0 -1 0\n", 1, "not a rotation matrix");
}

TEST_F(TrajectoryFiles, EmptyAndMissingFilesNameTheFile) {
  const std::string empty = write("empty.txt", "");
  expectError([&] { traj::readKitti(empty); }, empty, 0, "no poses");
  const std::string comments = write("comments.tum", "# only\n# comments\n\n");
  expectError([&] { traj::readTum(comments); }, comments, 0, "no poses");
  expectError([&] { traj::detectFormat(comments); }, comments, 0, "no poses");
  const std::string missing = path("does_not_exist.txt");
  expectError([&] { traj::readTum(missing); }, missing, 0, "cannot open");
  expectError([&] { traj::read(empty, "euroc"); }, empty, 0, "unknown trajectory format 'euroc'");
  const std::string odd = write("odd.txt", "1 2 3\n");
  expectError([&] { traj::detectFormat(odd); }, odd, 1, "cannot tell the format");
}

TEST_F(TrajectoryFiles, WriterReplacesAtomicallyAndReportsUnwritablePath) {
  const std::string file = path("out.txt");
  traj::writeKitti(file, makeTrajectory(3));
  traj::writeKitti(file, makeTrajectory(2));
  EXPECT_EQ(traj::readKitti(file).size(), 2u);
  EXPECT_EQ(std::distance(fs::directory_iterator(path("")), fs::directory_iterator()), 1);
  const std::string bad = path("no_such_dir/out.txt");
  expectError([&] { traj::writeTum(bad, makeTrajectory(2)); }, bad, 0, "cannot write");
}

TEST(TrajectorySharedData, ReadsEvoExampleFiles) {
  const fs::path dir = fs::path(BESLAM_SHARED_DATA) / "evo";
  if (!fs::exists(dir / "KITTI_00_gt.txt")) GTEST_SKIP() << "shared evo data not found at " << dir;
  EXPECT_EQ(traj::readKitti((dir / "KITTI_00_gt.txt").string()).size(), 4541u);
  EXPECT_EQ(traj::readKitti((dir / "KITTI_00_ORB.txt").string()).size(), 4541u);
  const Trajectory gt = traj::readTum((dir / "freiburg1_xyz-groundtruth.txt").string());
  EXPECT_EQ(gt.size(), 3000u);
  EXPECT_EQ(gt.stamps.front(), 1305031098.6659);
  EXPECT_EQ(traj::readTum((dir / "freiburg1_xyz-ORB_kf_mono.txt").string()).size(), 32u);
}
