#include "beslam/datasets/tum.hpp"

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include "beslam/datasets/dataset.hpp"
#include "test_util.hpp"

namespace beslam::datasets {
namespace {

using test::TempDir;
using test::writeText;

// A TUM folder named like the real ones: rgb.txt (with comments), rgb/*.png, groundtruth.txt at 100 Hz.
std::string makeTum(const TempDir& dir, const std::string& name, int width = 640, int height = 480) {
  const std::string root = dir / name;
  std::string rgb = "# color images\n# file: 'x.bag'\n# timestamp filename\n";
  for (int i = 0; i < 4; ++i) {
    const std::string stamp = std::to_string(1305031102.175304 + 0.0333 * i);
    test::writePng(root + "/rgb/" + stamp + ".png", width, height, 3, i);
    rgb += stamp + " rgb/" + stamp + ".png\n";
  }
  writeText(root + "/rgb.txt", rgb);
  std::string gt = "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n";
  for (int k = 0; k < 8; ++k)  // covers the first three frames only
    gt += std::to_string(1305031102.17 + 0.01 * k) + " " + std::to_string(0.01 * k) + " 0 0 0 0 0 1\n";
  writeText(root + "/groundtruth.txt", gt);
  return root;
}

TEST(Tum, DefaultIntrinsicsByFolderName) {
  EXPECT_EQ(tumDefaultIntrinsics("rgbd_dataset_freiburg1_xyz")->name, "fr1");
  EXPECT_DOUBLE_EQ(tumDefaultIntrinsics("rgbd_dataset_freiburg1_xyz")->camera.fx, 517.3);
  EXPECT_DOUBLE_EQ(tumDefaultIntrinsics("rgbd_dataset_freiburg2_desk")->camera.cy, 249.7);
  EXPECT_DOUBLE_EQ(tumDefaultIntrinsics("fr3_office")->camera.fy, 539.2);
  EXPECT_EQ(tumDefaultIntrinsics("fr3_office")->distortion[0], 0.0);
  EXPECT_FALSE(tumDefaultIntrinsics("my_sequence"));
}

TEST(Tum, PoseAtInterpolatesOrTakesNearest) {
  trajectory::Trajectory t;
  Eigen::Isometry3d A = Eigen::Isometry3d::Identity(), B = Eigen::Isometry3d::Identity();
  B.translation() << 1, 0, 0;
  B.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.push_back(10.0, A);
  t.push_back(10.1, B);
  const auto mid = poseAt(t, 10.025, 0.02);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->translation().x(), 0.25, 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(mid->linear()).angle(), 0.05, 1e-9);
  EXPECT_TRUE(poseAt(t, 10.11, 0.02)->isApprox(B));  // past the end: nearest within max_dt
  EXPECT_FALSE(poseAt(t, 10.2, 0.02));
  EXPECT_FALSE(poseAt(t, 9.9, 0.02));
  EXPECT_FALSE(poseAt(t, 10.05, 0.02, 0.05));  // gap too long to interpolate, neighbours too far
}

TEST(Tum, OpensWithDefaultsAndGroundTruth) {
  TempDir dir;
  const std::string root = makeTum(dir, "rgbd_dataset_freiburg1_xyz");
  DatasetOptions o;
  o.type = "tum";
  o.root = root;
  o.load_color = true;
  const auto ds = openDataset(o);
  ASSERT_EQ(ds->size(), 4u);
  EXPECT_EQ(ds->describe(),
            "TUM RGB-D rgbd_dataset_freiburg1_xyz (4 frames, fr1 default intrinsics, undistorted, ground truth for 3/4 "
            "frames)");
  EXPECT_DOUBLE_EQ(ds->camera().fx, 517.3);
  EXPECT_EQ(ds->camera().width, 640);
  EXPECT_FALSE(ds->T_cam_lidar());
  const auto gt = ds->groundTruth();
  ASSERT_EQ(gt->size(), 3u);
  EXPECT_NEAR(gt->stamps[1], 1305031102.175304 + 0.0333, 1e-6);
  EXPECT_NEAR(gt->poses[1].translation().x(), 0.01 * (1305031102.175304 + 0.0333 - 1305031102.17) / 0.01, 1e-6);
  // Loaded images are undistorted with the fr1 coefficients.
  const Frame f = ds->load(1);
  EXPECT_EQ(f.color.size(), cv::Size(640, 480));
  const cv::Matx33d K(517.3, 0, 318.6, 0, 516.5, 255.3, 0, 0, 1);
  cv::Mat expected;
  cv::undistort(test::pattern(640, 480, 3, 1), expected, K,
                std::vector<double>{0.2624, -0.9531, -0.0054, 0.0026, 1.1633});
  cv::Mat diff;
  cv::absdiff(f.color, expected, diff);
  EXPECT_LT(cv::mean(diff)[0], 8.0);  // same mapping, up to interpolation details
  EXPECT_GT(cv::norm(f.color, test::pattern(640, 480, 3, 1), cv::NORM_L1), 0);

  o.root = root + "/";  // a trailing slash still names the folder
  EXPECT_DOUBLE_EQ(openDataset(o)->camera().fx, 517.3);
  o.root = root;
  o.undistort = false;
  EXPECT_NE(openDataset(o)->describe().find("images left distorted"), std::string::npos);
  EXPECT_EQ(cv::norm(openDataset(o)->load(1).color, test::pattern(640, 480, 3, 1), cv::NORM_INF), 0);
  o.first = 3;
  const auto last = openDataset(o);
  EXPECT_EQ(last->size(), 1u);
  EXPECT_EQ(last->groundTruth()->size(), 0u);  // 33 ms past the last ground-truth sample
}

TEST(Tum, CameraFileAndErrors) {
  TempDir dir;
  const std::string root = makeTum(dir, "my_recording", 64, 48);
  DatasetOptions o;
  o.type = "tum";
  o.root = root;
  EXPECT_BESLAM_ERROR(openDataset(o), root, "dataset.calibration");
  writeText(dir / "cam.yaml", "model: pinhole\nwidth: 64\nheight: 48\nfx: 50\nfy: 50\ncx: 32\ncy: 24\n");
  o.calibration = dir / "cam.yaml";
  auto ds = openDataset(o);
  EXPECT_EQ(ds->camera().width, 64);
  EXPECT_DOUBLE_EQ(ds->camera().fx, 50);
  EXPECT_NE(ds->describe().find("camera file cam.yaml (pinhole)"), std::string::npos) << ds->describe();
  EXPECT_EQ(ds->load(0).gray.size(), cv::Size(64, 48));

  std::filesystem::remove_all(root + "/rgb");
  EXPECT_BESLAM_ERROR(openDataset(o), root + "/rgb/", "missing image", "rgb.txt");
  writeText(root + "/rgb.txt", "1.0 rgb/a.png\n0.5 rgb/b.png\n");
  EXPECT_BESLAM_ERROR(openDataset(o), root + "/rgb.txt:2:", "not increasing");
  writeText(root + "/rgb.txt", "1.0 rgb/a.png extra\n");
  EXPECT_BESLAM_ERROR(openDataset(o), root + "/rgb.txt:1:", "timestamp path");
  std::filesystem::remove(root + "/rgb.txt");
  EXPECT_BESLAM_ERROR(openDataset(o), root + "/rgb.txt", "missing image list");
  o.root = dir / "nothing";
  EXPECT_BESLAM_ERROR(openDataset(o), dir / "nothing", "missing TUM RGB-D sequence folder");
}

}  // namespace
}  // namespace beslam::datasets
