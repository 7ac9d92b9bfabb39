// The readers on the real KITTI excerpts in ../shared/data (skipped with a message where absent).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "beslam/datasets/dataset.hpp"
#include "beslam/datasets/kitti_calib.hpp"
#include "beslam/datasets/labels.hpp"
#include "beslam/datasets/velodyne.hpp"
#include "test_util.hpp"

namespace beslam::datasets {
namespace {

#define REQUIRE_SHARED(var, rel)                 \
  const std::string var = test::sharedData(rel); \
  if (var.empty()) GTEST_SKIP() << "shared data " << BESLAM_SHARED_DATA << "/" << rel << " is absent"

TEST(SharedData, KittiOdometry06BareCalib) {
  REQUIRE_SHARED(root, "kitti/odometry/sequences/06");
  DatasetOptions o = test::datasetOptions("kitti_odometry", test::sharedData("kitti/odometry"), "06");
  const auto ds = openDataset(o);
  EXPECT_EQ(ds->size(), 51u);
  EXPECT_EQ(ds->describe(), "KITTI odometry 06 (51 frames, image_0, ground truth)");
  EXPECT_EQ(ds->camera().width, 1226);
  EXPECT_EQ(ds->camera().height, 370);
  EXPECT_DOUBLE_EQ(ds->camera().fx, 707.0912);
  EXPECT_DOUBLE_EQ(ds->camera().cx, 601.8873);
  EXPECT_FALSE(ds->T_cam_lidar());  // the excerpt's calib has no Tr
  const auto gt = ds->groundTruth();
  ASSERT_TRUE(gt);
  ASSERT_EQ(gt->size(), 51u);
  EXPECT_TRUE(gt->poses[0].isApprox(Eigen::Isometry3d::Identity(), 1e-6));
  const Frame last = ds->load(50);
  EXPECT_EQ(last.index, 50);
  EXPECT_EQ(last.gray.size(), cv::Size(1226, 370));
  EXPECT_NEAR(last.timestamp, gt->stamps[50], 0);
  EXPECT_GT(last.timestamp, 5.0);
  // Colour camera is not in the excerpt (and the calib lacks P2).
  o.camera = "image_2";
  EXPECT_BESLAM_ERROR(openDataset(o), "image_2", "missing image folder");
}

TEST(SharedData, KittiOdometry00NamedCalib) {
  REQUIRE_SHARED(root, "kitti/odometry/sequences/00");
  DatasetOptions o = test::datasetOptions("kitti_odometry", test::sharedData("kitti/odometry"), "00");
  o.first = 100;
  o.step = 10;
  const auto ds = openDataset(o);
  EXPECT_EQ(ds->size(), 10u);
  EXPECT_DOUBLE_EQ(ds->camera().fx, 718.856);
  EXPECT_DOUBLE_EQ(ds->camera().cy, 185.2157);
  EXPECT_EQ(ds->camera().width, 1241);
  EXPECT_EQ(ds->camera().height, 376);
  const Frame f = ds->load(9);
  EXPECT_EQ(f.index, 190);
  EXPECT_EQ(f.gray.size(), cv::Size(1241, 376));
  const auto gt = ds->groundTruth();
  ASSERT_EQ(gt->size(), 10u);
  // Frames 100 and 190 of poses/00.txt (rows 101 and 191): the car has turned right and driven ~53 m.
  EXPECT_TRUE(gt->poses[0].translation().isApprox(Eigen::Vector3d(-4.934649, -2.926167, 84.31338), 1e-6));
  EXPECT_TRUE(gt->poses[9].translation().isApprox(Eigen::Vector3d(48.28879, -4.950044, 89.15280), 1e-6));
  EXPECT_DOUBLE_EQ(gt->stamps[9], f.timestamp);
  const KittiCalib calib = readOdometryCalib(root + "/calib.txt");
  EXPECT_NEAR(T_cami_rect0(*calib.P[1]).translation().x(), -0.537165719, 1e-8);  // stereo baseline
}

// Bottom-centred 3D box (KITTI label) contains p (rectified camera-0 coordinates).
bool insideBox(const ObjectLabel& box, const Eigen::Vector3d& p_rect0) {
  const Eigen::Vector3d d = p_rect0 - box.p_cam_bottom;
  const double c = std::cos(box.ry), s = std::sin(box.ry);
  const double x = c * d.x() - s * d.z();  // rotate by -ry about y into the box frame
  const double z = s * d.x() + c * d.z();
  return std::abs(x) <= box.l / 2 && std::abs(z) <= box.w / 2 && d.y() <= 0 && d.y() >= -box.h;
}

TEST(SharedData, KittiObject000008LidarLandsInCarBoxes) {
  REQUIRE_SHARED(root, "kitti/object/training/calib/000008.txt");
  DatasetOptions o = test::datasetOptions("kitti_object", test::sharedData("kitti/object/training"), "000008");
  o.load_lidar = true;
  o.load_color = true;
  const auto ds = openDataset(o);
  EXPECT_EQ(ds->describe(), "KITTI object 000008 (1 frame, image_2, velodyne)");
  const Frame f = ds->load(0);
  ASSERT_EQ(f.color.type(), CV_8UC3);
  const Camera& K = ds->camera();
  EXPECT_EQ(K.width, f.color.cols);
  EXPECT_DOUBLE_EQ(K.fx, 721.5377);
  ASSERT_TRUE(ds->T_cam_lidar());
  ASSERT_EQ(f.lidar_xyzi.size() % 4, 0u);
  ASSERT_GT(f.lidar_xyzi.size(), 4000u);

  const KittiCalib calib = readObjectCalib(o.root + "/calib/000008.txt");
  const Eigen::Isometry3d T_rect0_cam2 = T_cami_rect0(*calib.P[2]).inverse();  // labels are in rectified camera 0
  const auto labels = readObjectLabels(ds->labelPath());
  ASSERT_EQ(labels.size(), 10u);
  int cars_checked = 0;
  for (const ObjectLabel& car : labels) {
    if (car.type != "Car") continue;
    int in_box = 0, in_2d = 0;
    for (std::size_t i = 0; i + 3 < f.lidar_xyzi.size(); i += 4) {
      const Eigen::Vector3d p_lidar(f.lidar_xyzi[i], f.lidar_xyzi[i + 1], f.lidar_xyzi[i + 2]);
      const Eigen::Vector3d p_cam = *ds->T_cam_lidar() * p_lidar;
      if (p_cam.z() < 0.5 || !insideBox(car, T_rect0_cam2 * p_cam)) continue;
      const double u = K.fx * p_cam.x() / p_cam.z() + K.cx, v = K.fy * p_cam.y() / p_cam.z() + K.cy;
      if (u < 0 || v < 0 || u >= K.width || v >= K.height) continue;  // 2D boxes are clipped to the image
      ++in_box;
      const double margin = 3.0;
      if (u >= car.x1 - margin && u <= car.x2 + margin && v >= car.y1 - margin && v <= car.y2 + margin) ++in_2d;
    }
    if (in_box < 20) continue;  // outside the scan's field of view or too few returns
    ++cars_checked;
    EXPECT_GE(in_2d, 0.97 * in_box) << formatObjectRow(car) << ": " << in_2d << " of " << in_box;
  }
  EXPECT_GE(cars_checked, 5);  // all six cars are in the scan's field of view
}

TEST(SharedData, KittiTrackingLabelsAndCalib) {
  REQUIRE_SHARED(root, "kitti/tracking/training/label_02/0000.txt");
  const std::string training = test::sharedData("kitti/tracking/training");
  const KittiCalib object_calib = readObjectCalib(test::sharedData("kitti/object/training/calib/000008.txt"));
  for (int s = 0; s <= 10; ++s) {
    char seq[8];
    std::snprintf(seq, sizeof seq, "%04d", s);
    const std::string label_path = training + "/label_02/" + seq + ".txt";
    const auto labels = readTrackingLabels(label_path);
    std::ifstream in(label_path);
    const auto lines = std::count(std::istreambuf_iterator<char>(in), {}, '\n');
    EXPECT_EQ(static_cast<long>(labels.size()), lines) << label_path;
    std::int64_t previous = 0, max_frame = 0;
    for (const TrackingLabel& t : labels) {
      ASSERT_GE(t.frame, previous) << label_path;
      previous = t.frame;
      max_frame = std::max(max_frame, t.frame);
      EXPECT_EQ(t.track_id == -1, t.object.isDontCare()) << formatTrackingRow(t);
      if (!t.object.isDontCare()) {
        EXPECT_GT(t.object.h, 0) << formatTrackingRow(t);
      }
    }
    // Re-formatting reproduces the rows (the writer uses KITTI's own layout).
    const TrackingLabel again = parseTrackingRow(formatTrackingRow(labels[labels.size() / 2]));
    EXPECT_EQ(again.track_id, labels[labels.size() / 2].track_id);
    EXPECT_NEAR(again.object.p_cam_bottom.z(), labels[labels.size() / 2].object.p_cam_bottom.z(), 1e-6);

    const KittiCalib calib = readObjectCalib(training + "/calib/" + seq + ".txt");
    const auto T_cam2_velo = T_cami_velo(calib, 2);
    ASSERT_TRUE(T_cam2_velo) << seq;
    EXPECT_NEAR((*calib.P[2])(0, 0), 721.5377, 1e-9);
    // Sequences 0000-0010 are from 2011_09_26, the same rig calibration as object frame 000008.
    EXPECT_LT((T_cam2_velo->matrix() - T_cami_velo(object_calib, 2)->matrix()).cwiseAbs().maxCoeff(), 1e-6) << seq;

    // The ORB-SLAM3 ego poses have one row per frame (labels may stop before the last frame).
    const std::string ego = training + "/ego_poses_orbslam3/" + seq + ".txt";
    if (!test::sharedData("kitti/tracking/training/ego_poses_orbslam3/" + std::string(seq) + ".txt").empty()) {
      EXPECT_GE(trajectory::readKitti(ego).size(), static_cast<std::size_t>(max_frame + 1)) << ego;
    }
  }
  // The excerpt has no images, so the tracking layout names what is missing.
  DatasetOptions o = test::datasetOptions("kitti_tracking", training, "0000");
  EXPECT_BESLAM_ERROR(openDataset(o), "image_02/0000", "missing image folder");

  // With ego poses it opens image-less: one frame a pose row, camera 2 from the calibration, no image.
  o.ego_poses = training + "/ego_poses_orbslam3/0000.txt";
  if (!test::sharedData("kitti/tracking/training/ego_poses_orbslam3/0000.txt").empty()) {
    const auto ds = openDataset(o);
    EXPECT_EQ(ds->size(), trajectory::readKitti(o.ego_poses).size());
    EXPECT_NE(ds->describe().find("no images"), std::string::npos) << ds->describe();
    EXPECT_EQ(ds->camera().width, 1242);
    EXPECT_NEAR(ds->camera().fx, 721.5377, 1e-3);
    const Frame f = ds->load(5);
    EXPECT_TRUE(f.gray.empty());
    EXPECT_EQ(f.index, 5);
    EXPECT_DOUBLE_EQ(f.timestamp, 0.5);
    ASSERT_TRUE(ds->groundTruth().has_value());
  }
}

}  // namespace
}  // namespace beslam::datasets
