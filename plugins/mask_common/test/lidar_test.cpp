// The LiDAR chain against KITTI 000008's calibration, point masks, malformed calibration input.
#include "beslam/mask_common/lidar.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "kitti_data.hpp"

namespace fs = std::filesystem;
using namespace beslam;
using namespace beslam::mask;

TEST(LidarChain, MatchesKittiProjectionOf000008) {
  if (!fixture::haveKitti000008()) GTEST_SKIP() << "KITTI object 000008 not in " << fixture::kittiObjectDir();
  const std::string dir = fixture::kittiObjectDir();
  const formats::KittiCalib calib = formats::readObjectCalib(dir + "/calib/000008.txt");
  const std::vector<float> scan = formats::readVelodyneBin(dir + "/velodyne/000008.bin");
  ASSERT_GT(scan.size(), 4000u);
  const formats::Camera cam = formats::cameraFromProjection(*calib.P[2], 1242, 375, "P2");
  Intrinsics K;
  K.fx = cam.fx, K.fy = cam.fy, K.cx = cam.cx, K.cy = cam.cy, K.width = cam.width, K.height = cam.height;
  const Eigen::Isometry3d T = *formats::T_cami_velo(calib, 2);
  const CameraPoints pts = lidarToCamera(scan.data(), scan.size() / 4, 4, T, K, 0.5, 120);
  ASSERT_GT(pts.size(), 1000u);
  // Hand-composed KITTI chain: x = P2 * R0_rect * Tr_velo_to_cam * X (homogeneous), u = x0/x2, v = x1/x2.
  Eigen::Matrix4d R0 = Eigen::Matrix4d::Identity();
  R0.topLeftCorner<3, 3>() = calib.R0_rect;
  const Eigen::Matrix<double, 3, 4> chain = *calib.P[2] * R0 * calib.T_cam0_velo->matrix();
  size_t checked = 0, inside = 0;
  for (size_t i = 0; i < scan.size() / 4; i += 7) {
    const Eigen::Vector4d X(scan[4 * i], scan[4 * i + 1], scan[4 * i + 2], 1.0);
    const Eigen::Vector3d x = chain * X;
    if (x.z() < 0.5) continue;
    const double u = x.x() / x.z(), v = x.y() / x.z();
    if (u < -0.5 || v < -0.5 || u >= 1241.5 || v >= 374.5) continue;
    ++inside;
    // Find the same point among the kept ones (same camera z within float precision).
    const Eigen::Vector3d p = T * X.head<3>();
    EXPECT_NEAR(K.fx * p.x() / p.z() + K.cx, u, 1e-6);
    EXPECT_NEAR(K.fy * p.y() / p.z() + K.cy, v, 1e-6);
    ++checked;
  }
  EXPECT_GT(checked, 100u);
  // Every kept point is in front of the camera and inside the image; the count matches the chain's.
  for (size_t i = 0; i < pts.size(); ++i) {
    ASSERT_GE(pts.p[i].z(), 0.5f);
    ASSERT_GE(pts.uv[i].x, -0.5f);
    ASSERT_LT(pts.uv[i].x, 1241.5f);
  }
  EXPECT_NEAR(static_cast<double>(pts.size()) / 7, static_cast<double>(inside), 0.02 * inside + 5);
}

TEST(LidarChain, LabelledCarsOf000008HoldTheirPoints) {
  if (!fixture::haveKitti000008()) GTEST_SKIP() << "KITTI object 000008 not in " << fixture::kittiObjectDir();
  const std::string dir = fixture::kittiObjectDir();
  // Labels are in rectified camera 0: the chain up to R0_rect.
  const CameraPoints pts = fixture::camera0Scan000008().pts;
  int id = 0, cars = 0;
  for (const auto& l : formats::readObjectLabels(dir + "/label_2/000008.txt")) {
    if (l.type != "Car") continue;
    ++cars;
    const beslam_box3d b = fixture::boxFromLabel(l, id++);
    const size_t n = pointsNearBox(b, pts, 0.0, 0.15).size();
    EXPECT_GT(n, l.p_cam_bottom.z() < 25 ? 50u : 5u) << "car at z = " << l.p_cam_bottom.z();
  }
  EXPECT_EQ(cars, 6);
}

TEST(PointMask, DenseSplatsFillTheObjectSparseOnesAreRefused) {
  CameraPoints pts;
  // A 40 x 20 px block of points every 2 columns and 6 rows.
  for (int v = 100; v < 120; v += 6)
    for (int u = 200; u < 240; u += 2) {
      pts.p.emplace_back(0.f, 0.f, 10.f);
      pts.uv.emplace_back(static_cast<float>(u), static_cast<float>(v));
    }
  std::vector<int> idx(pts.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<int>(i);
  const cv::Rect roi(190, 90, 60, 40);
  const cv::Mat region(roi.size(), CV_8UC1, cv::Scalar(255));
  PointMaskParams params;
  params.min_coverage = 0.2;
  const cv::Mat m = pointMask(pts, idx, roi, region, params);
  ASSERT_FALSE(m.empty());
  EXPECT_EQ(m.at<uint8_t>(110 - 90, 220 - 190), 255);  // between beams: closed
  EXPECT_EQ(m.at<uint8_t>(2, 2), 0);
  const std::vector<int> few(idx.begin(), idx.begin() + 10);
  EXPECT_TRUE(pointMask(pts, few, roi, region, params).empty());
}

namespace {

// A minimal synthetic sequence folder with a given calib.txt, for the tool's error paths.
std::string sequenceWithCalib(const std::string& name, const std::string& calib) {
  const fs::path d = fs::temp_directory_path() / ("beslam_mask_" + name + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d / "image_0");
  fs::create_directories(d / "label_02");
  fs::create_directories(d / "instance");
  std::ofstream(d / "calib.txt") << calib;
  std::ofstream(d / "label_02" / "00.txt") << "";
  const cv::Mat img(20, 30, CV_8UC1, cv::Scalar(0));
  cv::imwrite((d / "image_0" / "000000.png").string(), img);
  return d.string();
}

int runTool(const std::string& args, std::string& err) {
  const std::string log = (fs::temp_directory_path() / ("mask_bench_err" + std::to_string(::getpid()))).string();
  const int rc =
      std::system((std::string(BESLAM_BINARY_DIR) + "/bin/mask_bench " + args + " >/dev/null 2>" + log).c_str());
  std::ifstream in(log);
  err.assign(std::istreambuf_iterator<char>(in), {});
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

}  // namespace

TEST(MalformedCalibration, ToolNamesTheFileAndLine) {
  if (!fs::exists(std::string(BESLAM_BINARY_DIR) + "/bin/mask_bench")) GTEST_SKIP() << "mask_bench not built";
  const std::string P = "7 0 3 0 0 7 2 0 0 0 1 0";
  struct Case {
    std::string name, calib, expect;
  } cases[] = {
      {"short_row", "P0: 7 0 3 0 0 7 2\nP1: " + P + "\nP2: " + P + "\nP3: " + P + "\nR0_rect: 1 0 0 0 1 0 0 0 1\n",
       "calib.txt:1"},
      {"not_number", "P0: " + P + "\nP1: " + P + "\nP2: " + P + "\nP3: " + P + "\nR0_rect: 1 0 0 0 1 0 0 0 x\n",
       "calib.txt:5"},
      {"no_r0", "P0: " + P + "\nP1: " + P + "\nP2: " + P + "\nP3: " + P + "\n", "calib.txt"},
      {"no_lidar", "P0: " + P + "\nP1: " + P + "\nP2: " + P + "\nP3: " + P + "\nR0_rect: 1 0 0 0 1 0 0 0 1\n",
       "Tr_velo_to_cam"},
  };
  for (const Case& c : cases) {
    const std::string seq = sequenceWithCalib(c.name, c.calib);
    std::string err;
    const int rc = runTool("generate --sequence " + seq + " --out " + seq + "/out --variant lidar_contour", err);
    EXPECT_EQ(rc, 1) << c.name << ": " << err;
    EXPECT_NE(err.find(c.expect), std::string::npos) << c.name << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << c.name << ": one line: " << err;
    fs::remove_all(seq);
  }
}
