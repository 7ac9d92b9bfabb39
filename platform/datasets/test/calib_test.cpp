#include <gtest/gtest.h>

#include "beslam/datasets/kitti_calib.hpp"
#include "test_util.hpp"

namespace beslam::datasets {
namespace {

using test::TempDir;
using test::writeText;

const char* kP0 =
    "7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 0.000000000000e+00 0.000000000000e+00 7.188560000000e+02 "
    "1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 0.000000000000e+00";
const char* kP1 =
    "7.188560000000e+02 0.000000000000e+00 6.071928000000e+02 -3.861448000000e+02 0.000000000000e+00 "
    "7.188560000000e+02 1.852157000000e+02 0.000000000000e+00 0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 "
    "0.000000000000e+00";
const char* kP2 =
    "7.215377e+02 0 6.095593e+02 4.485728e+01 0 7.215377e+02 1.728540e+02 2.163791e-01 0 0 1 2.745884e-03";
const char* kP3 =
    "7.215377e+02 0 6.095593e+02 -3.395242e+02 0 7.215377e+02 1.728540e+02 2.199936e+00 0 0 1 2.729905e-03";
const char* kR0 =
    "9.999239e-01 9.837760e-03 -7.445048e-03 -9.869795e-03 9.999421e-01 -4.278459e-03 7.402527e-03 4.351614e-03 "
    "9.999631e-01";
const char* kTr =
    "7.533745e-03 -9.999714e-01 -6.166020e-04 -4.069766e-03 1.480249e-02 7.280733e-04 -9.998902e-01 -7.631618e-02 "
    "9.998621e-01 7.523790e-03 1.480755e-02 -2.717806e-01";
const char* kTrImu =
    "9.999976e-01 7.553071e-04 -2.035826e-03 -8.086759e-01 -7.854027e-04 9.998898e-01 -1.482298e-02 3.195559e-01 "
    "2.024406e-03 1.482454e-02 9.998881e-01 -7.997231e-01";

std::string objectCalibText(bool tracking_names) {
  std::string s;
  s += std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\nP2: " + kP2 + "\nP3: " + kP3 + "\n";
  if (tracking_names)
    s += std::string("R_rect ") + kR0 + "\nTr_velo_cam " + kTr + "\nTr_imu_velo " + kTrImu + "\n";
  else
    s += std::string("R0_rect: ") + kR0 + "\nTr_velo_to_cam: " + kTr + "\nTr_imu_to_velo: " + kTrImu + "\n";
  return s;
}

TEST(KittiCalib, OdometryNamedRows) {
  TempDir dir;
  writeText(dir / "calib.txt", std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\n");
  const KittiCalib calib = readOdometryCalib(dir / "calib.txt");
  ASSERT_TRUE(calib.P[0] && calib.P[1]);
  EXPECT_FALSE(calib.P[2]);
  EXPECT_FALSE(calib.T_cam0_velo);
  const Camera camera = cameraFromProjection(*calib.P[0], 1241, 376, "P0");
  EXPECT_DOUBLE_EQ(camera.fx, 718.856);
  EXPECT_DOUBLE_EQ(camera.cy, 185.2157);
  // Right camera: t = K^-1 P1[:,3] = (-baseline, 0, 0).
  EXPECT_NEAR(T_cami_rect0(*calib.P[1]).translation().x(), -386.1448 / 718.856, 1e-12);
}

TEST(KittiCalib, OdometryBareRowsTakeOfficialOrder) {
  TempDir dir;
  writeText(dir / "calib.txt", std::string(kP0) + "\n" + kP1 + "\n" + kP2 + "\n" + kP3 + "\n" + kTr + "\n");
  const KittiCalib calib = readOdometryCalib(dir / "calib.txt");
  ASSERT_TRUE(calib.P[3] && calib.T_cam0_velo);
  EXPECT_DOUBLE_EQ((*calib.P[3])(0, 3), -339.5242);
  EXPECT_DOUBLE_EQ(calib.T_cam0_velo->translation().z(), -0.2717806);
  EXPECT_TRUE(calib.R0_rect.isIdentity());  // odometry Tr lands in the rectified frame already
}

TEST(KittiCalib, MalformedRowsNameFileAndLine) {
  TempDir dir;
  const std::string path = dir / "calib.txt";
  writeText(path, std::string("P0: ") + kP0 + "\nP1: 1 2 3\n");
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path + ":2:", "P1 has 3 values, expected 12");
  writeText(path, std::string("P0: ") + kP0 + "\nP1: 7.1 abc 3 4 5 6 7 8 9 10 11 12\n");
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path + ":2:", "'abc'", "not a number");
  writeText(path, std::string(kP0) + "\n" + kP0 + "\n" + kP0 + "\n" + kP0 + "\n" + kTr + "\n" + kTr + "\n");
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path + ":6:", "unnamed row");
  writeText(path, std::string("P1: ") + kP1 + "\n");
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path, "missing calibration entry P0");
  writeText(path, std::string("P0: ") + kP0 + "\nP0: " + kP0 + "\n");
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path + ":2:", "duplicate");
  writeText(path, "");
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path, "empty");
  EXPECT_BESLAM_ERROR(readOdometryCalib(dir / "nope.txt"), dir / "nope.txt");
  writeText(path, "P0: 700 0.5 600 0 0 700 180 0 0 0 1 0\n");  // skew
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path + ":1:", "not a rectified pinhole");
}

// Probe: a P0 row starting with nan or inf was taken for a row named "nan", so P1 was read as P0 (APE
// 0.099 m instead of 0.043 m on KITTI 06). Non-finite and non-positive focal lengths are errors.
TEST(KittiCalib, NonFiniteOrNonPositiveP0IsAnError) {
  TempDir dir;
  const std::string path = dir / "calib.txt";
  const std::string rest = std::string(kP0).substr(std::string(kP0).find(' '));
  for (const char* bad : {"nan", "inf", "-inf", "1e999"}) {
    writeText(path, std::string(bad) + rest + "\n" + kP1 + "\n" + kP2 + "\n" + kP3 + "\n" + kTr + "\n");
    EXPECT_BESLAM_ERROR(readOdometryCalib(path),
                        path + ":1:", std::string("'") + bad + "' in P0 is not a finite number");
    writeText(path, std::string("P0: ") + bad + rest + "\nP1: " + kP1 + "\n");
    EXPECT_BESLAM_ERROR(readOdometryCalib(path),
                        path + ":1:", std::string("'") + bad + "' in P0 is not a finite number");
  }
  writeText(path, "0 0 600 0 0 700 180 0 0 0 1 0\n" + std::string(kP1) + "\n");
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path + ":1:", "P0: focal lengths must be finite and positive");
  writeText(path, "P0: 700 0 600 0 0 -700 180 0 0 0 1 0\n");
  EXPECT_BESLAM_ERROR(readOdometryCalib(path), path + ":1:", "P0: focal lengths must be finite and positive");
}

TEST(KittiCalib, ObjectAndTrackingNamesAgree) {
  TempDir dir;
  writeText(dir / "object.txt", objectCalibText(false));
  writeText(dir / "tracking.txt", objectCalibText(true));
  const KittiCalib a = readObjectCalib(dir / "object.txt");
  const KittiCalib b = readObjectCalib(dir / "tracking.txt");
  ASSERT_TRUE(a.T_cam0_velo && b.T_cam0_velo && a.T_velo_imu && b.T_velo_imu);
  EXPECT_TRUE(a.R0_rect.isApprox(b.R0_rect));
  EXPECT_TRUE(a.T_cam0_velo->isApprox(*b.T_cam0_velo));
  EXPECT_TRUE(a.T_velo_imu->isApprox(*b.T_velo_imu));
  EXPECT_DOUBLE_EQ(a.R0_rect(0, 1), 9.837760e-03);
}

TEST(KittiCalib, ObjectCalibErrors) {
  TempDir dir;
  const std::string path = dir / "calib.txt";
  writeText(path, std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\nP2: " + kP2 + "\nP3: " + kP3 + "\n");
  EXPECT_BESLAM_ERROR(readObjectCalib(path), path, "R0_rect or R_rect");
  writeText(path, objectCalibText(false) + "R1: 1 2\n");  // extra unknown entries are fine
  EXPECT_NO_THROW(readObjectCalib(path));
  writeText(path, std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\nP2: " + kP2 + "\nP3: " + kP3 +
                      "\nR0_rect: 2 0 0 0 1 0 0 0 1\n");
  EXPECT_BESLAM_ERROR(readObjectCalib(path), path + ":5:", "not a rotation");
  writeText(path, std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\nP2: " + kP2 + "\nP3: " + kP3 + "\nR0_rect: " + kR0 +
                      "\nTr_velo_to_cam: 1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_BESLAM_ERROR(readObjectCalib(path), path + ":6:", "Tr_velo_to_cam has 11 values");
}

// The composed T_cam_lidar reproduces the KITTI projection chain x = P_i * R0_rect * Tr * X exactly.
TEST(KittiCalib, TcamLidarMatchesProjectionChain) {
  TempDir dir;
  writeText(dir / "calib.txt", objectCalibText(false));
  const KittiCalib calib = readObjectCalib(dir / "calib.txt");
  Eigen::Matrix4d R0 = Eigen::Matrix4d::Identity();
  R0.topLeftCorner<3, 3>() = calib.R0_rect;
  for (int cam = 0; cam < 4; ++cam) {
    const auto T_cam_velo = T_cami_velo(calib, cam);
    ASSERT_TRUE(T_cam_velo);
    const Matrix34d& P = *calib.P[static_cast<std::size_t>(cam)];
    const Camera K = cameraFromProjection(P, 0, 0, "P");
    for (const Eigen::Vector3d& p_velo :
         {Eigen::Vector3d(10, 2, -1), Eigen::Vector3d(25, -6, 0.5), Eigen::Vector3d(5, 0, 0)}) {
      const Eigen::Vector3d x = P * R0 * calib.T_cam0_velo->matrix() * p_velo.homogeneous();
      const Eigen::Vector3d p_cam = *T_cam_velo * p_velo;
      EXPECT_NEAR(K.fx * p_cam.x() / p_cam.z() + K.cx, x.x() / x.z(), 1e-9) << "camera " << cam;
      EXPECT_NEAR(K.fy * p_cam.y() / p_cam.z() + K.cy, x.y() / x.z(), 1e-9) << "camera " << cam;
      EXPECT_NEAR(p_cam.z(), x.z(), 1e-9);  // depth is preserved (P's last row is [0 0 1 tz])
    }
  }
  // Colour camera 2 sits ~6 cm left of camera 0: t_x = P2[0,3] / fx (+ cx * tz term).
  EXPECT_NEAR(T_cami_rect0(*calib.P[2]).translation().x(), (44.85728 - 609.5593 * 2.745884e-03) / 721.5377, 1e-12);
  KittiCalib no_lidar = calib;
  no_lidar.T_cam0_velo.reset();
  EXPECT_FALSE(T_cami_velo(no_lidar, 2));
  EXPECT_FALSE(T_cami_velo(calib, 4));
}

TEST(KittiCalib, RawCalibFiles) {
  TempDir dir;
  writeText(dir / "calib_cam_to_cam.txt",
            std::string("calib_time: 09-Jan-2012 13:57:47\ncorner_dist: 9.950000e-02\nS_00: 1.392000e+03 5.120000e+02\n"
                        "R_rect_00: ") +
                kR0 + "\nP_rect_00: " + kP0 + "\nP_rect_02: " + kP2 + "\n");
  writeText(dir / "calib_velo_to_cam.txt",
            "calib_time: 15-Mar-2012 11:37:16\nR: 7.533745e-03 -9.999714e-01 -6.166020e-04 1.480249e-02 7.280733e-04 "
            "-9.998902e-01 9.998621e-01 7.523790e-03 1.480755e-02\nT: -4.069766e-03 -7.631618e-02 -2.717806e-01\n"
            "delta_f: 0.000000e+00 0.000000e+00\ndelta_c: 0.000000e+00 0.000000e+00\n");
  const KittiCalib calib = readRawCalib(dir / "calib_cam_to_cam.txt", dir / "calib_velo_to_cam.txt");
  ASSERT_TRUE(calib.P[0] && calib.P[2] && !calib.P[1] && calib.T_cam0_velo);
  EXPECT_DOUBLE_EQ(calib.T_cam0_velo->translation().y(), -7.631618e-02);
  EXPECT_DOUBLE_EQ(calib.T_cam0_velo->linear()(2, 0), 9.998621e-01);
  EXPECT_TRUE(T_cami_velo(calib, 2));
  // Without the LiDAR file: cameras only.
  EXPECT_FALSE(readRawCalib(dir / "calib_cam_to_cam.txt", dir / "absent.txt").T_cam0_velo);
  writeText(dir / "calib_velo_to_cam.txt", "R: 1 0 0 0 1 0 0 0 1\nT: 1 2\n");
  EXPECT_BESLAM_ERROR(readRawCalib(dir / "calib_cam_to_cam.txt", dir / "calib_velo_to_cam.txt"),
                      dir / "calib_velo_to_cam.txt:2:", "T has 2 values, expected 3");
}

}  // namespace
}  // namespace beslam::datasets
