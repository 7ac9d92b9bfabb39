#include "beslam/datasets/labels.hpp"

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace beslam::datasets {
namespace {

using test::TempDir;

TEST(Labels, ObjectRows) {
  const ObjectLabel car =
      parseObjectRow("Car 0.88 3 -0.69 0.00 192.37 402.31 374.00 1.60 1.57 3.23 -2.70 1.74 3.68 -1.29");
  EXPECT_EQ(car.type, "Car");
  EXPECT_DOUBLE_EQ(car.truncated, 0.88);
  EXPECT_EQ(car.occluded, 3);
  EXPECT_DOUBLE_EQ(car.x2, 402.31);
  EXPECT_DOUBLE_EQ(car.l, 3.23);
  EXPECT_DOUBLE_EQ(car.p_cam_bottom.z(), 3.68);
  EXPECT_DOUBLE_EQ(car.ry, -1.29);
  EXPECT_FALSE(car.score);
  const ObjectLabel det = parseObjectRow("Pedestrian 0 0 0.1 1 2 3 4 1.7 0.6 0.8 1 1.5 10 0.2 0.93");
  ASSERT_TRUE(det.score);
  EXPECT_DOUBLE_EQ(*det.score, 0.93);
  const ObjectLabel dc = parseObjectRow(
      "DontCare -1.00 -1 -10.00 800.38 163.67 825.45 184.07 -1.00 -1.00 -1.00 -1000.00 -1000.00 -1000.00 -10.00");
  EXPECT_TRUE(dc.isDontCare());
  EXPECT_EQ(dc.occluded, -1);
  EXPECT_EQ(parseObjectRow(formatObjectRow(car)).x1, car.x1);
}

TEST(Labels, TrackingRowsRoundTrip) {
  const std::string row =
      "0 2 Pedestrian 0 0 -2.523309 1106.137292 166.576807 1204.470628 323.876144 1.714062 0.767881 0.972283 "
      "6.301919 1.652419 8.455685 -1.900245";
  const TrackingLabel t = parseTrackingRow(row);
  EXPECT_EQ(t.frame, 0);
  EXPECT_EQ(t.track_id, 2);
  EXPECT_EQ(t.object.type, "Pedestrian");
  EXPECT_DOUBLE_EQ(t.object.p_cam_bottom.x(), 6.301919);
  EXPECT_EQ(formatTrackingRow(t), row);  // KITTI's own 6-decimal layout, integral truncation
  TrackingLabel scored = t;
  scored.object.score = 0.5;
  scored.object.truncated = 1;
  EXPECT_EQ(formatTrackingRow(scored),
            "0 2 Pedestrian 1" + row.substr(std::string("0 2 Pedestrian 0").size()) + " 0.500000");
  const TrackingLabel back = parseTrackingRow(formatTrackingRow(scored));
  ASSERT_TRUE(back.object.score);
  EXPECT_DOUBLE_EQ(*back.object.score, 0.5);
  const TrackingLabel dc = parseTrackingRow(
      "0 -1 DontCare -1 -1 -10.000000 219.310000 188.490000 245.500000 218.560000 -1000.000000 -1000.000000 "
      "-1000.000000 -10.000000 -1.000000 -1.000000 -1.000000");
  EXPECT_EQ(dc.track_id, -1);
  EXPECT_TRUE(dc.object.isDontCare());
}

TEST(Labels, FileErrorsNameLine) {
  TempDir dir;
  const std::string path = dir / "0000.txt";
  const std::string good = "3 1 Car 0 0 -1.5 10 20 30 40 1.5 1.6 3.9 1 1.7 20 -1.5\n";
  test::writeText(path, good + "\n" + good + "3 1 Car 0 0 -1.5 10 20 30 40 1.5 1.6 3.9 1 1.7 20\n");
  EXPECT_BESLAM_ERROR(readTrackingLabels(path), path + ":4:", "16 fields, expected 17 or 18");
  test::writeText(path, good + "x 1 Car 0 0 -1.5 10 20 30 40 1.5 1.6 3.9 1 1.7 20 -1.5\n");
  EXPECT_BESLAM_ERROR(readTrackingLabels(path), path + ":2:", "frame 'x'");
  test::writeText(path, good + "3 1 Car 0 0 -1.5 10 20 30 4o 1.5 1.6 3.9 1 1.7 20 -1.5\n");
  EXPECT_BESLAM_ERROR(readTrackingLabels(path), path + ":2:", "y2 '4o'");
  test::writeText(path, good + good);
  EXPECT_EQ(readTrackingLabels(path).size(), 2u);
  test::writeText(path, "Car 0 0 -1.5 10 20 30 40 1.5 1.6 3.9 1 1.7 20 nan\n");
  EXPECT_BESLAM_ERROR(readObjectLabels(path), path + ":1:", "ry 'nan'");
  test::writeText(path, "1.5 0 0 -1.5 10 20 30 40 1.5 1.6 3.9 1 1.7 20 1\n");
  EXPECT_BESLAM_ERROR(readObjectLabels(path), path + ":1:", "class name");
  EXPECT_BESLAM_ERROR(readObjectLabels(dir / "none.txt"), dir / "none.txt");
}

TEST(Labels, ObjectMotionRowsAndErrors) {
  TempDir dir;
  const std::string path = dir / "objects_motion.txt";
  test::writeText(path, "# frame track_id moving speed_m_s\n0 1 0 0.0\n\n  # note\n0 2 1 7.5\n1 2 1 7.4\n");
  const auto moving = readObjectMotion(path);
  ASSERT_EQ(moving.size(), 3u);
  EXPECT_FALSE(moving.at({0, 1}));
  EXPECT_TRUE(moving.at({0, 2}));
  EXPECT_TRUE(moving.at({1, 2}));
  for (const char* row : {"0 1 2 0.0", "0 1 1", "0 1 1 0.0 x", "0 1 1 nan", "0.5 1 1 0.0", "0 1 1.0 0.0"}) {
    test::writeText(path, std::string("0 1 0 0.0\n") + row + "\n");
    EXPECT_BESLAM_ERROR(readObjectMotion(path), path + ":2:", "expected 'frame track_id moving(0/1) speed'");
  }
  EXPECT_BESLAM_ERROR(readObjectMotion(dir / "none.txt"), dir / "none.txt");
}

}  // namespace
}  // namespace beslam::datasets
