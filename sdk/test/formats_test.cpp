// The SDK's formats component: trajectory and label rows (good rows, and bad rows giving one error that
// names the file and the line), box geometry, alignment.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "beslam/formats/align.hpp"
#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"
#include "beslam/formats/geometry.hpp"
#include "beslam/formats/labels.hpp"
#include "beslam/formats/ply.hpp"
#include "beslam/formats/trajectory.hpp"
#include "beslam/test/scratch_dir.hpp"

namespace beslam::formats {
namespace {

namespace fs = std::filesystem;

class Files : public beslam::test::ScratchDir {
 protected:
  // The one error message reading `path` gives (empty when it reads).
  template <class F>
  static std::string errorOf(F&& read) {
    try {
      read();
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(Files, KittiAndTumRowsReadAndRoundTripExactly) {
  const std::string kitti =
      write("k.txt", "# comment\n1 0 0 0.5 0 1 0 -0.25 0 0 1 3\r\n\n0 -1 0 1e-3 1 0 0 2 0 0 1 0\n");
  const Trajectory k = readKitti(kitti);
  ASSERT_EQ(k.size(), 2u);
  EXPECT_EQ(k.stamps[1], 1.0);
  EXPECT_EQ(k.poses[0].translation(), Eigen::Vector3d(0.5, -0.25, 3));
  EXPECT_EQ(k.poses[1].linear()(0, 1), -1.0);
  EXPECT_EQ(detectFormat(kitti), "kitti");

  const std::string tum = write("t.txt", "0.1 1 2 3 0 0 0 2\n0.2,1,2,3.5,0,0,0.7071067811865476,0.7071067811865476\n");
  const Trajectory t = readTum(tum);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_TRUE(t.poses[0].linear().isIdentity(0));  // quaternion normalised on read
  EXPECT_NEAR(t.poses[1].linear()(1, 0), 1.0, 1e-15);
  EXPECT_EQ(detectFormat(tum), "tum");

  writeTum(write("out.tum", ""), t);
  const Trajectory back = readTum(path("out.tum"));
  EXPECT_EQ(back.stamps, t.stamps);
  EXPECT_EQ(back.poses[1].translation(), t.poses[1].translation());
  writeKitti(write("out.kitti", ""), k);
  EXPECT_EQ(readKitti(path("out.kitti")).poses[1].matrix(), k.poses[1].matrix());
}

TEST_F(Files, PlyMeshesRoundTripAndBadFilesNameTheFile) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(10, 0, -2);
  writePlyMesh(path("m.ply"), m, T);
  const TriangleMesh back = readPlyMesh(path("m.ply"));
  ASSERT_EQ(back.vertices.size(), 4u);
  EXPECT_EQ(back.faces, m.faces);
  EXPECT_EQ(back.vertices[1], Eigen::Vector3d(11, 0, -2));  // written through T, exact in float
  // ASCII with extra vertex properties (a map with colours) reads its x y z.
  const std::string ascii =
      write("a.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nproperty uchar red\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n0 0 0 9\n1 0 0 9\n0 1 0 9\n3 0 1 2\n");
  EXPECT_EQ(readPlyMesh(ascii).vertices[2], Eigen::Vector3d(0, 1, 0));
  // Truncated, not PLY, a quad, an index past the vertices: one error each, naming the file.
  const std::string bytes = readFile(path("m.ply"));
  const std::string cut = write("cut.ply", bytes.substr(0, bytes.size() - 5));
  EXPECT_NE(errorOf([&] { readPlyMesh(cut); }).find("cut.ply: PLY file truncated"), std::string::npos);
  EXPECT_NE(errorOf([&] { readPlyMesh(write("x.ply", "solid x\n")); }).find("x.ply: not a PLY file"),
            std::string::npos);
  const std::string quad = write("q.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\nend_header\n0 0 0\n4 0 0 0 0\n");
  EXPECT_NE(errorOf([&] { readPlyMesh(quad); }).find("q.ply: PLY face 0 unreadable"), std::string::npos);
  const std::string past = write("p.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\nend_header\n0 0 0\n3 0 0 5\n");
  EXPECT_NE(errorOf([&] { readPlyMesh(past); }).find("p.ply: PLY face index out of range"), std::string::npos);
}

TEST_F(Files, BadTrajectoryRowsNameTheFileAndLine) {
  const std::string short_row = write("short.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_EQ(errorOf([&] { readKitti(short_row); }),
            short_row + ":2: expected 12 numbers per row (KITTI format), found 11");
  const std::string word = write("word.txt", "0.1 1 2 x 0 0 0 1\n");
  EXPECT_EQ(errorOf([&] { readTum(word); }), word + ":1: column 4: 'x' is not a number");
  const std::string nan = write("nan.txt", "# t x y z qx qy qz qw\n0.1 1 2 nan 0 0 0 1\n");
  EXPECT_EQ(errorOf([&] { readTum(nan); }), nan + ":2: column 4: non-finite value 'nan'");
  const std::string zero_q = write("zq.txt", "0.1 1 2 3 0 0 0 0\n");
  EXPECT_EQ(errorOf([&] { readTum(zero_q); }), zero_q + ":1: quaternion has zero length");
  const std::string skew = write("skew.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(errorOf([&] { readKitti(skew); }).find(skew + ":1: the 3x3 part is not a rotation matrix"),
            std::string::npos);
  const std::string empty = write("empty.txt", "# nothing\n\n");
  EXPECT_EQ(errorOf([&] { readKitti(empty); }), empty + ": no poses in file (empty or only comments)");
  EXPECT_EQ(errorOf([&] { detectFormat(write("nine.txt", "1 2 3 4 5 6 7 8 9\n")); }),
            path("nine.txt") + ":1: cannot tell the format: 9 numbers per row (KITTI has 12, TUM has 8)");
  EXPECT_NE(errorOf([&] { readKitti(path("absent.txt")); }).find("absent.txt: cannot open file"), std::string::npos);
  EXPECT_EQ(errorOf([&] { read(short_row, "csv"); }),
            short_row + ": unknown trajectory format 'csv' (expected kitti or tum)");
}

TEST_F(Files, LabelRowsParseAndBadRowsNameTheFileAndLine) {
  const ObjectLabel o = parseObjectRow("Car 0.50 1 -1.5 10 20 110 80 1.5 1.6 3.9 2 1.7 12 0.1 -0.3", "a.txt", 3);
  EXPECT_EQ(o.type, "Car");
  EXPECT_EQ(o.occluded, 1);
  EXPECT_EQ(o.p_cam_bottom, Eigen::Vector3d(2, 1.7, 12));
  ASSERT_TRUE(o.score);
  EXPECT_EQ(*o.score, -0.3);
  const TrackingLabel t = parseTrackingRow("4 7 Van 0 0 0 1 2 3 4 2 1.8 4.5 -1 1.6 20 0.3");
  EXPECT_EQ(t.frame, 4);
  EXPECT_EQ(t.track_id, 7);
  EXPECT_FALSE(t.object.score);
  EXPECT_EQ(formatTrackingRow(t),
            "4 7 Van 0 0 0.000000 1.000000 2.000000 3.000000 4.000000 2.000000 1.800000 4.500000 "
            "-1.000000 1.600000 20.000000 0.300000");

  const std::string labels = write("labels.txt",
                                   "Car 0 0 0 1 2 3 4 1.5 1.6 3.9 2 1.7 12 0.1\n\n"
                                   "Car 0 0 0 1 2 3 4 1.5 1.6 wide 2 1.7 12 0.1\n");
  EXPECT_EQ(errorOf([&] { readObjectLabels(labels); }), labels + ":3: l 'wide' is not a number");
  const std::string tracking = write("0001.txt", "0 1 Car 0 0 0 1 2 3 4 1.5 1.6 3.9 2 1.7 12\n");
  EXPECT_EQ(errorOf([&] { readTrackingLabels(tracking); }),
            tracking + ":1: tracking label row has 16 fields, expected 17 or 18");
  EXPECT_EQ(errorOf([&] { parseTrackingRow("-2 1 Car 0 0 0 1 2 3 4 1.5 1.6 3.9 2 1.7 12 0.1", "x.txt", 9); }),
            "x.txt:9: negative frame number");
  EXPECT_EQ(errorOf([&] { parseObjectRow("3 0 0 0 1 2 3 4 1.5 1.6 3.9 2 1.7 12 0.1", "y.txt", 2); }),
            "y.txt:2: type '3' is a number, expected a class name");

  const std::string motion = write("motion.txt", "# frame track moving speed\n0 3 1 4.5\n0 4 0 0\n1 3 2 0\n");
  EXPECT_EQ(errorOf([&] { readObjectMotion(motion); }),
            motion + ":4: expected 'frame track_id moving(0/1) speed', got '1 3 2 0'");
}

TEST(Geometry, KittiBoxesAndPosesConvert) {
  int32_t class_id = -5;
  EXPECT_TRUE(kittiClass("Person_sitting", class_id));
  EXPECT_EQ(class_id, BESLAM_CLASS_PEDESTRIAN);
  EXPECT_FALSE(kittiClass("Bus", class_id));
  const beslam_box3d box = boxFromKitti(BESLAM_CLASS_CAR, 1.5, 1.6, 4.0, 1, 2, 10, M_PI / 2);
  EXPECT_EQ(box.center_cam[1], 1.25);
  EXPECT_EQ(box.track_id, -1);
  EXPECT_EQ(box.motion_state, BESLAM_MOTION_UNKNOWN);
  const Eigen::Matrix<double, 3, 8> corners = boxCorners(box);
  // yaw 90 degrees: the length runs along -z; bottom corners at y = 2.
  EXPECT_NEAR(corners.row(2).maxCoeff(), 12.0, 1e-12);
  EXPECT_NEAR(corners.row(2).minCoeff(), 8.0, 1e-12);
  EXPECT_NEAR(corners(1, 0), 2.0, 1e-12);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(4, 5, 6);
  EXPECT_TRUE(toIsometry(toPose(T)).isApprox(T, 0));
  EXPECT_STREQ(className(BESLAM_CLASS_VAN), "Van");
  EXPECT_STREQ(motionName(BESLAM_MOTION_DYNAMIC), "dynamic");
}

TEST(Align, UmeyamaRecoversASimilarityAndRefusesALine) {
  std::vector<Eigen::Vector3d> est = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 3}, {1, 1, 1}};
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<Eigen::Vector3d> ref;
  for (const auto& p : est) ref.push_back(2.5 * (R * p) + Eigen::Vector3d(1, -2, 0.5));
  const Similarity s = umeyama(ref, est, est.size(), true);
  EXPECT_NEAR(s.scale, 2.5, 1e-12);
  EXPECT_TRUE(s.R_ref_est.isApprox(R, 1e-12));
  const PositionError e = positionError(est, ref);
  EXPECT_LT(e.rmse, 1e-12);
  EXPECT_EQ(e.count, 5u);
  const std::vector<Eigen::Vector3d> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  EXPECT_THROW(umeyama(line, line, 3, true), Error);
}

}  // namespace
}  // namespace beslam::formats
