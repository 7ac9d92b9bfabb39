// Every layout on small synthetic folders: the happy path, the frame range, and each malformed case.
#include <gtest/gtest.h>

#include <cstdio>

#include "beslam/datasets/dataset.hpp"
#include "beslam/datasets/kitti_calib.hpp"
#include "test_util.hpp"

namespace beslam::datasets {
namespace {

using test::TempDir;
using test::writeText;

constexpr int kW = 48, kH = 32;
const std::string kP0 = "700 0 24 0 0 710 16 0 0 0 1 0";
const std::string kP1 = "700 0 24 -378 0 710 16 0 0 0 1 0";
const std::string kP2 = "705 0 25 44.8 0 705 15 0.2 0 0 1 0.0027";
const std::string kP3 = "705 0 25 -339.5 0 705 15 2.2 0 0 1 0.0027";
const std::string kR0 =
    "0.9999239 0.00983776 -0.007445048 -0.009869795 0.9999421 -0.004278459 0.007402527 0.004351614 0.9999631";
const std::string kTr = "0 -1 0 0.1 0 0 -1 -0.08 1 0 0 -0.27";
// The four projection rows as the odometry, tracking and object calibration files write them.
const std::string kProjections = "P0: " + kP0 + "\nP1: " + kP1 + "\nP2: " + kP2 + "\nP3: " + kP3 + "\n";

std::string name6(int i) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%06d", i);
  return buf;
}

std::string poseRow(double z) { return "1 0 0 0 0 1 0 0 0 0 1 " + std::to_string(z) + "\n"; }

// sequences/07 with image_0 (grey), image_2 (colour), velodyne, calib with Tr, times, poses.
struct OdometryFixture {
  TempDir dir;
  std::string seq;
  explicit OdometryFixture(int frames = 5) : seq(dir / "sequences/07") {
    std::string times, poses;
    for (int i = 0; i < frames; ++i) {
      test::writePng(seq + "/image_0/" + name6(i) + ".png", kW, kH, 1, i);
      test::writePng(seq + "/image_2/" + name6(i) + ".png", kW, kH, 3, i);
      test::writeScan(seq + "/velodyne/" + name6(i) + ".bin", 10 + i);
      times += std::to_string(0.1 * i) + "\n";
      poses += poseRow(1.0 * i);
    }
    writeText(seq + "/calib.txt", kProjections + "Tr: " + kTr + "\n");
    writeText(seq + "/times.txt", times);
    writeText(dir / "poses/07.txt", poses);
  }
  DatasetOptions options() const { return test::datasetOptions("kitti_odometry", dir.str(), "07"); }
};

TEST(KittiOdometry, OpensAndLoads) {
  OdometryFixture fx;
  DatasetOptions o = fx.options();
  o.load_lidar = true;
  const auto ds = openDataset(o);
  EXPECT_EQ(ds->size(), 5u);
  EXPECT_EQ(ds->describe(), "KITTI odometry 07 (5 frames, image_0, velodyne, ground truth)");
  EXPECT_EQ(ds->camera().width, kW);
  EXPECT_EQ(ds->camera().height, kH);
  EXPECT_DOUBLE_EQ(ds->camera().fx, 700);
  EXPECT_DOUBLE_EQ(ds->camera().fy, 710);
  ASSERT_TRUE(ds->T_cam_lidar());
  EXPECT_NEAR(ds->T_cam_lidar()->translation().y(), -0.08, 1e-12);
  const Frame f = ds->load(3);
  EXPECT_EQ(f.index, 3);
  EXPECT_DOUBLE_EQ(f.timestamp, 0.3);
  EXPECT_EQ(f.gray.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(f.gray, test::pattern(kW, kH, 1, 3), cv::NORM_INF), 0);
  EXPECT_TRUE(f.color.empty());
  EXPECT_EQ(f.lidar_xyzi.size(), 4u * 13);
  EXPECT_NE(f.lidar_path.find("velodyne/000003.bin"), std::string::npos);
  const auto gt = ds->groundTruth();
  ASSERT_TRUE(gt);
  ASSERT_EQ(gt->size(), 5u);
  EXPECT_DOUBLE_EQ(gt->poses[4].translation().z(), 4.0);
  EXPECT_DOUBLE_EQ(gt->stamps[4], 0.4);
  EXPECT_BESLAM_ERROR(ds->load(5), "out of range");
  // Without load_lidar the scan is only named.
  EXPECT_TRUE(openDataset(fx.options())->load(0).lidar_xyzi.empty());
}

// A camera file replaces P0's intrinsics (and KITTI's 1.65 m); `name` renames the sequence (a synth rendering).
TEST(KittiOdometry, CameraFileAndName) {
  OdometryFixture fx;
  DatasetOptions o = fx.options();
  o.name = "synthetic urban_loop";
  writeText(fx.dir / "cam.yaml", "model: pinhole\nwidth: " + std::to_string(kW) + "\nheight: " + std::to_string(kH) +
                                     "\nfx: 650\nfy: 650\ncx: 20\ncy: 10\nheight_over_road: 2.5\n");
  o.calibration = fx.dir / "cam.yaml";
  const auto ds = openDataset(o);
  EXPECT_EQ(ds->describe(),
            "synthetic urban_loop (5 frames, image_0, camera file cam.yaml (pinhole), velodyne, ground truth)");
  EXPECT_DOUBLE_EQ(ds->camera().fx, 650);
  EXPECT_DOUBLE_EQ(ds->camera().cx, 20);
  EXPECT_DOUBLE_EQ(*ds->cameraHeight(), 2.5);
  EXPECT_DOUBLE_EQ(*openDataset(fx.options())->cameraHeight(), 1.65);
  EXPECT_EQ(cv::norm(ds->load(3).gray, test::pattern(kW, kH, 1, 3), cv::NORM_INF), 0);  // no distortion: as read
  writeText(fx.dir / "cam.yaml",
            "model: pinhole\nwidth: 99\nheight: " + std::to_string(kH) + "\nfx: 650\nfy: 650\ncx: 20\ncy: 10\n");
  EXPECT_BESLAM_ERROR(openDataset(o), fx.dir / "cam.yaml", "width x height is 99x", "the camera file must describe");
}

TEST(KittiOdometry, FrameRangeAndColourCamera) {
  OdometryFixture fx(7);
  DatasetOptions o = fx.options();
  o.first = 1;
  o.last = 5;
  o.step = 2;
  o.camera = "image_2";
  o.load_color = true;
  const auto ds = openDataset(o);
  ASSERT_EQ(ds->size(), 3u);
  EXPECT_EQ(ds->describe(), "KITTI odometry 07 (3 frames, image_2, frames 1-5 step 2 of 7, velodyne, ground truth)");
  EXPECT_DOUBLE_EQ(ds->camera().fx, 705);
  const Frame f = ds->load(2);
  EXPECT_EQ(f.index, 5);
  EXPECT_EQ(f.color.type(), CV_8UC3);
  EXPECT_EQ(f.gray.type(), CV_8UC1);
  // Ground truth re-expressed for camera 2: T_cam2_cam0 * T_world_cam0 * T_cam0_cam2 (world = camera 2 at frame 0).
  const auto gt = ds->groundTruth();
  ASSERT_EQ(gt->size(), 3u);
  EXPECT_DOUBLE_EQ(gt->stamps[0], 0.1);
  Matrix34d P2;
  P2 << 705, 0, 25, 44.8, 0, 705, 15, 0.2, 0, 0, 1, 0.0027;
  const Eigen::Isometry3d T_cam2_cam0 = T_cami_rect0(P2);
  Eigen::Isometry3d T_world_cam0 = Eigen::Isometry3d::Identity();
  T_world_cam0.translation().z() = 5;
  EXPECT_TRUE(gt->poses[2].isApprox(T_cam2_cam0 * T_world_cam0 * T_cam2_cam0.inverse()));
  // T_cam_lidar for camera 2 includes the P2 offset.
  o.camera = "image_0";
  const auto ds0 = openDataset(o);
  EXPECT_TRUE(ds->T_cam_lidar()->isApprox(T_cam2_cam0 * *ds0->T_cam_lidar()));
}

// A camera blackout: the frames in the ranges load all black (grey and colour, same size and type), every
// other frame and everything else about the dataset unchanged; a range holding no selected frame is an error.
TEST(BlackFrames, FramesInTheRangesAreBlackOthersUntouched) {
  OdometryFixture fx(7);
  DatasetOptions o = fx.options();
  o.camera = "image_2";
  o.load_color = true;
  o.load_lidar = true;
  const auto plain = openDataset(o);
  const auto ds = blackOut(openDataset(o), parseFrameRanges("2-3,5"));
  ASSERT_EQ(ds->size(), 7u);
  EXPECT_EQ(ds->describe(), plain->describe() + ", black frames 2-3,5");
  for (std::size_t i = 0; i < ds->size(); ++i) {
    const Frame f = ds->load(i), p = plain->load(i);
    const bool black = i == 2 || i == 3 || i == 5;
    EXPECT_EQ(ds->frameNumber(i), static_cast<std::int64_t>(i));
    ASSERT_EQ(f.gray.size(), p.gray.size());
    ASSERT_EQ(f.gray.type(), p.gray.type());
    ASSERT_EQ(f.color.size(), p.color.size());
    ASSERT_EQ(f.color.type(), p.color.type());
    ASSERT_GT(cv::norm(p.gray, cv::NORM_INF), 0) << "the fixture's frame " << i << " is black already";
    if (black) {
      EXPECT_EQ(cv::norm(f.gray, cv::NORM_INF), 0) << "frame " << i;
      EXPECT_EQ(cv::norm(f.color, cv::NORM_INF), 0) << "frame " << i;
    } else {
      EXPECT_EQ(cv::norm(f.gray, p.gray, cv::NORM_INF), 0) << "frame " << i;
      EXPECT_EQ(cv::norm(f.color, p.color, cv::NORM_INF), 0) << "frame " << i;
    }
    EXPECT_EQ(f.index, p.index);
    EXPECT_EQ(f.timestamp, p.timestamp);
    EXPECT_EQ(f.lidar_xyzi, p.lidar_xyzi) << "frame " << i;  // only the camera goes dark
  }
  ASSERT_TRUE(ds->groundTruth());
  EXPECT_EQ(ds->groundTruth()->size(), plain->groundTruth()->size());
  EXPECT_EQ(ds->camera().width, plain->camera().width);
  EXPECT_TRUE(ds->T_cam_lidar()->isApprox(*plain->T_cam_lidar()));
}

TEST(BlackFrames, ARangeOutsideTheSelectedFramesIsAnError) {
  OdometryFixture fx(7);
  DatasetOptions o = fx.options();
  o.first = 2;
  o.last = 4;
  EXPECT_BESLAM_ERROR(blackOut(openDataset(o), parseFrameRanges("5-9")),
                      "range 5-9 holds none of the 3 selected frames (numbers 2..4)");
  EXPECT_BESLAM_ERROR(blackOut(openDataset(o), parseFrameRanges("0-1,3")), "range 0-1 holds none");
  o.step = 2;  // frames 2 and 4
  EXPECT_BESLAM_ERROR(blackOut(openDataset(o), parseFrameRanges("3")), "range 3 holds none");
  EXPECT_EQ(blackOut(openDataset(o), parseFrameRanges("3-4"))->size(), 2u);
}

TEST(KittiOdometry, LayoutErrors) {
  OdometryFixture fx;
  DatasetOptions o = fx.options();
  const std::string seq = fx.seq;

  DatasetOptions bad = o;
  bad.root = fx.dir / "nowhere";
  EXPECT_BESLAM_ERROR(openDataset(bad), bad.root, "missing KITTI odometry root folder");
  writeText(fx.dir / "a_file", "not a folder\n");  // probe: a root that is a file said the folder is missing
  bad.root = fx.dir / "a_file";
  EXPECT_BESLAM_ERROR(openDataset(bad), bad.root, "is a file, not a folder (expected the KITTI odometry root folder)");
  bad = o;
  bad.sequence = "11";
  EXPECT_BESLAM_ERROR(openDataset(bad), fx.dir / "sequences/11", "missing KITTI odometry sequence folder");
  bad = o;
  bad.type = "kitti";
  EXPECT_BESLAM_ERROR(openDataset(bad), "unknown dataset type 'kitti'", "kitti_odometry");
  bad = o;
  bad.camera = "left";
  EXPECT_BESLAM_ERROR(openDataset(bad), "unknown camera 'left'");
  bad = o;
  bad.camera = "image_1";
  EXPECT_BESLAM_ERROR(openDataset(bad), seq + "/image_1", "missing image folder");
  bad = o;
  bad.first = 9;
  EXPECT_BESLAM_ERROR(openDataset(bad), seq + "/image_0", "selects none");
  bad = o;
  bad.step = 0;
  EXPECT_BESLAM_ERROR(openDataset(bad), "step must be >= 1");
  bad = o;
  bad.first = 3;
  bad.last = 2;
  EXPECT_BESLAM_ERROR(openDataset(bad), "last (2) < first (3)");

  // Poses with the wrong count.
  writeText(fx.dir / "poses/07.txt", poseRow(0) + poseRow(1));
  EXPECT_BESLAM_ERROR(openDataset(o), fx.dir / "poses/07.txt", "2 poses", "5 frames");
  std::filesystem::remove(fx.dir / "poses/07.txt");
  EXPECT_FALSE(openDataset(o)->groundTruth());  // ground truth is optional
  // ego_poses replaces poses/NN.txt and is taken as is for the chosen camera.
  writeText(fx.dir / "mine.txt", poseRow(0) + poseRow(2) + poseRow(4) + poseRow(6) + poseRow(8));
  bad = o;
  bad.ego_poses = fx.dir / "mine.txt";
  bad.camera = "image_2";
  ASSERT_TRUE(openDataset(bad)->groundTruth());
  EXPECT_DOUBLE_EQ(openDataset(bad)->groundTruth()->poses[3].translation().z(), 6.0);
  EXPECT_TRUE(openDataset(bad)->groundTruth()->poses[3].linear().isIdentity());

  // times.txt: missing, malformed, wrong count.
  const std::string times = test::readBytes(seq + "/times.txt");
  writeText(seq + "/times.txt", "0\n0.1\n0.2\n");
  EXPECT_BESLAM_ERROR(openDataset(o), seq + "/times.txt", "3 timestamps", "5 images");
  writeText(seq + "/times.txt", "0\n0.1\nzero\n0.3\n0.4\n");
  EXPECT_BESLAM_ERROR(openDataset(o), seq + "/times.txt:3:", "'zero'");
  // Probe: two frames swapped, or one repeated, gave APE 3.30 m instead of 0.043 m without a word.
  writeText(seq + "/times.txt", "0\n0.2\n0.1\n0.3\n0.4\n");
  EXPECT_BESLAM_ERROR(openDataset(o), seq + "/times.txt:3:", "timestamp 0.1 is not after the previous one");
  writeText(seq + "/times.txt", "0\n0.1\n0.1\n0.3\n0.4\n");
  EXPECT_BESLAM_ERROR(openDataset(o), seq + "/times.txt:3:", "must increase strictly");
  std::filesystem::remove(seq + "/times.txt");
  EXPECT_BESLAM_ERROR(openDataset(o), seq + "/times.txt", "missing timestamps file");
  writeText(seq + "/times.txt", times);

  // Calibration: bad row, missing P for the chosen camera, missing file.
  const std::string calib = test::readBytes(seq + "/calib.txt");
  writeText(seq + "/calib.txt", "P0: " + kP0 + "\nP1: 1 2 3\n");
  EXPECT_BESLAM_ERROR(openDataset(o), seq + "/calib.txt:2:", "P1 has 3 values");
  writeText(seq + "/calib.txt", "P0: " + kP0 + "\nP1: " + kP1 + "\n");
  bad = o;
  bad.camera = "image_2";
  EXPECT_BESLAM_ERROR(openDataset(bad), seq + "/calib.txt", "no P2 for image_2");
  EXPECT_FALSE(openDataset(o)->T_cam_lidar());  // no Tr: no LiDAR extrinsics
  std::filesystem::remove(seq + "/calib.txt");
  EXPECT_BESLAM_ERROR(openDataset(o), seq + "/calib.txt", "missing calibration file");
  writeText(seq + "/calib.txt", calib);

  // A gap in the image numbering.
  std::filesystem::remove(seq + "/image_0/000002.png");
  EXPECT_BESLAM_ERROR(openDataset(o), seq + "/image_0/000002.png", "missing frame");
  std::filesystem::remove_all(seq + "/image_0");
  bad = o;
  bad.camera = "auto";
  EXPECT_EQ(openDataset(bad)->describe().find("image_2") != std::string::npos, true);  // auto falls back
  std::filesystem::remove_all(seq + "/image_2");
  EXPECT_BESLAM_ERROR(openDataset(o), seq, "neither image_0 nor image_2");
}

TEST(KittiOdometry, LoadErrorsNameTheFile) {
  OdometryFixture fx;
  DatasetOptions o = fx.options();
  o.load_lidar = true;
  const auto ds = openDataset(o);
  const std::string png = fx.seq + "/image_0/000001.png";
  test::truncateFile(png, std::filesystem::file_size(png) - 20);
  EXPECT_BESLAM_ERROR(ds->load(1), png, "truncated PNG");
  const std::string bin = fx.seq + "/velodyne/000002.bin";
  test::truncateFile(bin, 18);
  EXPECT_BESLAM_ERROR(ds->load(2), bin, "truncated LiDAR scan");
  std::filesystem::remove(fx.seq + "/velodyne/000003.bin");
  EXPECT_BESLAM_ERROR(ds->load(3), fx.seq + "/velodyne/000003.bin", "missing LiDAR scan");
  std::filesystem::remove(fx.seq + "/image_0/000004.png");
  EXPECT_BESLAM_ERROR(ds->load(4), fx.seq + "/image_0/000004.png", "missing image");
  test::writePng(fx.seq + "/image_0/000004.png", kW + 2, kH, 1);
  EXPECT_BESLAM_ERROR(ds->load(4), fx.seq + "/image_0/000004.png", "50x32, expected 48x32");
  EXPECT_NO_THROW(ds->load(0));
}

// training/{image_02,velodyne}/0003/, calib/0003.txt (tracking names), label_02/0003.txt.
struct TrackingFixture {
  TempDir dir;
  explicit TrackingFixture(int frames = 4) {
    std::string poses;
    for (int i = 0; i < frames; ++i) {
      test::writePng(dir / ("image_02/0003/" + name6(i) + ".png"), kW, kH, 3, i);
      test::writeScan(dir / ("velodyne/0003/" + name6(i) + ".bin"), 5);
      poses += poseRow(0.5 * i);
    }
    writeText(dir / "calib/0003.txt",
              kProjections + "R_rect " + kR0 + "\nTr_velo_cam " + kTr + "\nTr_imu_velo " + kTr + "\n");
    writeText(dir / "label_02/0003.txt", "0 0 Car 0 0 -1.5 10 20 30 40 1.5 1.6 3.9 1 1.7 20 -1.5\n");
    writeText(dir / "ego/0003.txt", poses);
  }
  DatasetOptions options() const { return test::datasetOptions("kitti_tracking", dir.str(), "0003"); }
};

TEST(KittiTracking, OpensAndLoads) {
  TrackingFixture fx;
  DatasetOptions o = fx.options();
  o.load_color = true;
  o.load_lidar = true;
  auto ds = openDataset(o);
  EXPECT_EQ(ds->describe(), "KITTI tracking 0003 (4 frames, image_02, velodyne, labels)");
  EXPECT_EQ(ds->labelPath(), fx.dir / "label_02/0003.txt");
  EXPECT_DOUBLE_EQ(ds->camera().fx, 705);
  ASSERT_TRUE(ds->T_cam_lidar());
  KittiCalib calib = readObjectCalib(fx.dir / "calib/0003.txt");
  EXPECT_TRUE(ds->T_cam_lidar()->isApprox(*T_cami_velo(calib, 2)));
  EXPECT_FALSE(ds->groundTruth());
  const Frame f = ds->load(2);
  EXPECT_DOUBLE_EQ(f.timestamp, 0.2);
  EXPECT_EQ(f.color.type(), CV_8UC3);
  EXPECT_EQ(f.lidar_xyzi.size(), 20u);
  EXPECT_EQ(f.label_path, ds->labelPath());

  o.ego_poses = fx.dir / "ego/0003.txt";
  o.first = 1;
  ds = openDataset(o);
  ASSERT_TRUE(ds->groundTruth());
  EXPECT_EQ(ds->groundTruth()->size(), 3u);
  EXPECT_DOUBLE_EQ(ds->groundTruth()->poses[0].translation().z(), 0.5);
  EXPECT_DOUBLE_EQ(ds->groundTruth()->stamps[0], 0.1);
}

TEST(KittiTracking, LayoutErrors) {
  TrackingFixture fx;
  DatasetOptions o = fx.options();
  DatasetOptions bad = o;
  bad.ego_poses = fx.dir / "ego/none.txt";
  EXPECT_BESLAM_ERROR(openDataset(bad), fx.dir / "ego/none.txt", "missing pose file");
  writeText(fx.dir / "ego/short.txt", poseRow(0));
  bad.ego_poses = fx.dir / "ego/short.txt";
  EXPECT_BESLAM_ERROR(openDataset(bad), fx.dir / "ego/short.txt", "1 poses", "4 frames");
  bad = o;
  bad.camera = "image_0";
  EXPECT_BESLAM_ERROR(openDataset(bad), "image_00/0003", "missing image folder");
  bad = o;
  bad.sequence = "0004";
  EXPECT_BESLAM_ERROR(openDataset(bad), fx.dir / "calib/0004.txt", "missing calibration file");
  writeText(fx.dir / "calib/0004.txt", "P0: " + kP0 + "\n");
  EXPECT_BESLAM_ERROR(openDataset(bad), fx.dir / "calib/0004.txt", "missing calibration entry P1");
  writeText(fx.dir / "calib/0004.txt", kProjections + "R_rect " + kR0 + "\n");
  EXPECT_BESLAM_ERROR(openDataset(bad), "image_02/0004", "missing image folder");

  std::filesystem::remove(fx.dir / "label_02/0003.txt");
  std::filesystem::remove_all(fx.dir / "velodyne");
  const auto ds = openDataset(o);
  EXPECT_TRUE(ds->labelPath().empty());
  EXPECT_FALSE(ds->T_cam_lidar());
  EXPECT_EQ(ds->describe(), "KITTI tracking 0003 (4 frames, image_02)");
}

// raw/2011_09_26/{calib_cam_to_cam.txt, calib_velo_to_cam.txt, 2011_09_26_drive_0001_sync/...}
struct RawFixture {
  TempDir dir;
  std::string date = dir / "2011_09_26";
  std::string drive = date + "/2011_09_26_drive_0001_sync";
  RawFixture() {
    std::string stamps;
    const char* times[] = {"2011-09-26 13:02:25.964389445", "2011-09-26 13:02:26.068486171",
                           "2011-09-26 13:02:26.172551120"};
    for (int i = 0; i < 3; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "%010d", i);
      test::writePng(drive + "/image_00/data/" + name + ".png", kW, kH, 1, i);
      test::writePng(drive + "/image_02/data/" + name + ".png", kW, kH, 3, i);
      test::writeScan(drive + "/velodyne_points/data/" + name + ".bin", 3);
      stamps += std::string(times[i]) + "\n";
    }
    writeText(drive + "/image_00/timestamps.txt", stamps);
    writeText(drive + "/image_02/timestamps.txt", stamps);
    writeText(date + "/calib_cam_to_cam.txt",
              "calib_time: 09-Jan-2012 13:57:47\ncorner_dist: 9.950000e-02\nR_rect_00: " + kR0 + "\nP_rect_00: " + kP0 +
                  "\nP_rect_01: " + kP1 + "\nP_rect_02: " + kP2 + "\nP_rect_03: " + kP3 + "\n");
    writeText(date + "/calib_velo_to_cam.txt",
              "calib_time: 15-Mar-2012 11:37:16\nR: 0 -1 0 0 0 -1 1 0 0\nT: 0.1 -0.08 -0.27\n");
  }
  DatasetOptions options() const { return test::datasetOptions("kitti_raw", dir.str(), "2011_09_26_drive_0001_sync"); }
};

TEST(KittiRaw, OpensAndLoads) {
  RawFixture fx;
  DatasetOptions o = fx.options();
  o.load_lidar = true;
  auto ds = openDataset(o);
  EXPECT_EQ(ds->describe(), "KITTI raw 2011_09_26_drive_0001_sync (3 frames, image_00, velodyne)");
  const Frame f = ds->load(2);
  EXPECT_NEAR(f.timestamp, 26.172551120 - 25.964389445, 1e-9);
  EXPECT_EQ(f.index, 2);
  EXPECT_EQ(f.lidar_xyzi.size(), 12u);
  ASSERT_TRUE(ds->T_cam_lidar());
  Eigen::Matrix3d R0;
  R0 << 0.9999239, 0.00983776, -0.007445048, -0.009869795, 0.9999421, -0.004278459, 0.007402527, 0.004351614, 0.9999631;
  EXPECT_TRUE(ds->T_cam_lidar()->translation().isApprox(R0 * Eigen::Vector3d(0.1, -0.08, -0.27)));
  // The date folder itself as root, colour camera.
  o.root = fx.date;
  o.camera = "image_2";
  ds = openDataset(o);
  EXPECT_DOUBLE_EQ(ds->camera().fx, 705);
  EXPECT_NE(ds->describe().find("image_02"), std::string::npos);
}

TEST(KittiRaw, LayoutErrors) {
  RawFixture fx;
  DatasetOptions o = fx.options();
  writeText(fx.drive + "/image_00/timestamps.txt", "2011-09-26 13:02:25.964389445\n2011-09-26 13:02:26\n");
  EXPECT_BESLAM_ERROR(openDataset(o), fx.drive + "/image_00/timestamps.txt", "2 timestamps", "3 images");
  writeText(fx.drive + "/image_00/timestamps.txt", "2011-09-26 13:02:25.964389445\nyesterday\nnow\n");
  EXPECT_BESLAM_ERROR(openDataset(o), fx.drive + "/image_00/timestamps.txt:2:", "'yesterday'");
  // The times_poses fuzz target's promises (tests/fuzz/corpus/times_poses/raw-nan-seconds.txt,
  // raw-backwards.txt): sscanf reads "nan" as seconds, and times that go back were taken as they were.
  writeText(fx.drive + "/image_00/timestamps.txt",
            "2011-09-26 13:02:25.964389445\n2011-09-26 13:02:nan\n2011-09-26 13:02:26.2\n");
  EXPECT_BESLAM_ERROR(openDataset(o), fx.drive + "/image_00/timestamps.txt:2:", "'2011-09-26 13:02:nan'");
  writeText(fx.drive + "/image_00/timestamps.txt",
            "2011-09-26 13:02:25.964389445\n2011-09-26 13:02:26.1\n2011-09-26 13:02:26.1\n");
  EXPECT_BESLAM_ERROR(openDataset(o), fx.drive + "/image_00/timestamps.txt:3:", "is not after the previous one");
  writeText(fx.drive + "/image_00/timestamps.txt",
            "2011-09-26 13:-1:25.964389445\n2011-09-26 13:02:26.1\n2011-09-26 13:02:26.2\n");
  EXPECT_BESLAM_ERROR(openDataset(o), fx.drive + "/image_00/timestamps.txt:1:", "expected a timestamp like");
  std::filesystem::remove(fx.date + "/calib_cam_to_cam.txt");
  EXPECT_BESLAM_ERROR(openDataset(o), fx.date + "/calib_cam_to_cam.txt", "missing calibration file");
  DatasetOptions bad = o;
  bad.sequence = "2011_09_26_drive_0002_sync";
  EXPECT_BESLAM_ERROR(openDataset(bad), "2011_09_26_drive_0002_sync", "missing KITTI raw drive folder");
  bad.sequence = "short";
  EXPECT_BESLAM_ERROR(openDataset(bad), "kitti_raw needs a sequence");
}

// training/{image_2,velodyne,calib,label_2}/NNNNNN
struct ObjectFixture {
  TempDir dir;
  ObjectFixture() {
    for (int i : {3, 7}) {
      test::writePng(dir / ("image_2/" + name6(i) + ".png"), kW, kH, 3, i);
      test::writeScan(dir / ("velodyne/" + name6(i) + ".bin"), 4);
      writeText(dir / ("calib/" + name6(i) + ".txt"),
                kProjections + "R0_rect: " + kR0 + "\nTr_velo_to_cam: " + kTr + "\n");
    }
    writeText(dir / "label_2/000007.txt", "Car 0 0 -1.5 10 20 30 40 1.5 1.6 3.9 1 1.7 20 -1.5\n");
  }
  DatasetOptions options(const std::string& sequence) const {
    return test::datasetOptions("kitti_object", dir.str(), sequence);
  }
};

TEST(KittiObject, OneFrameOrAll) {
  ObjectFixture fx;
  auto ds = openDataset(fx.options("000007"));
  EXPECT_EQ(ds->describe(), "KITTI object 000007 (1 frame, image_2, velodyne)");
  EXPECT_EQ(ds->labelPath(), fx.dir / "label_2/000007.txt");
  EXPECT_EQ(ds->load(0).index, 7);
  EXPECT_TRUE(ds->T_cam_lidar());
  ds = openDataset(fx.options(""));
  ASSERT_EQ(ds->size(), 2u);
  EXPECT_EQ(ds->load(0).index, 3);
  EXPECT_TRUE(ds->load(0).label_path.empty());
  EXPECT_EQ(ds->load(1).label_path, fx.dir / "label_2/000007.txt");
  EXPECT_BESLAM_ERROR(openDataset(fx.options("000005")), fx.dir / "image_2/000005.png", "missing image");
  EXPECT_BESLAM_ERROR(openDataset(fx.options("abc")), "frame number");
  DatasetOptions with_poses = fx.options("000007");
  with_poses.ego_poses = fx.dir / "poses.txt";
  EXPECT_BESLAM_ERROR(openDataset(with_poses), "ego_poses is not supported for kitti_object");
  // Frames with different calibration cannot share one dataset.
  writeText(fx.dir / "calib/000007.txt", "P0: " + kP0 + "\nP1: " + kP1 +
                                             "\nP2: 710 0 25 44.8 0 705 15 0.2 0 0 1 0.0027\nP3: " + kP3 +
                                             "\nR0_rect: " + kR0 + "\nTr_velo_to_cam: " + kTr + "\n");
  EXPECT_BESLAM_ERROR(openDataset(fx.options("")), fx.dir / "calib/000007.txt", "calibration differs");
  std::filesystem::remove(fx.dir / "calib/000003.txt");
  EXPECT_BESLAM_ERROR(openDataset(fx.options("000003")), fx.dir / "calib/000003.txt", "missing calibration file");
}

}  // namespace
}  // namespace beslam::datasets
