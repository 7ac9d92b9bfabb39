// AB3DMOT rows and KITTI labels: geometry, classes, scores, filters, every malformed-input path (stop
// and skip policies), and the real shared files.
#include "beslam/detector_replay/replay.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace beslam::detector_replay;

namespace {

using beslam::test::TempDir;

const std::string kRow0 =
    "0,2,298.3125,165.1800,458.2292,293.4391,8.2981,1.9605,1.8137,4.7549,-4.5720,1.8435,13.5308,-2.1125,-1.7867";
const std::string kRow1 = "1,1,700,150,740,260,-0.4501,1.70,0.60,0.80,2.0,1.60,9.0,0.5,0.3";

using Reader = void (*)(const std::string&, const Filter&, Policy, ScoreTransform, DetectionTable&, Report&);

// Expects `read` to stop on `row` (line 2, after the good `first`) with a message naming file:2 and
// `cause`, and its skip policy to leave the row out and count it.
void expectReaderRowError(Reader read, const std::string& first, const std::string& row, const std::string& cause) {
  TempDir dir;
  const std::string file = dir.write("det.txt", first + "\n" + row + "\n");
  DetectionTable table;
  Report report;
  try {
    read(file, Filter{}, Policy::stop, ScoreTransform::none, table, report);
    ADD_FAILURE() << "accepted: " << row;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file + ":2"), std::string::npos) << what;
    EXPECT_NE(what.find(cause), std::string::npos) << what;
  }
  DetectionTable t2;
  Report r2;
  read(file, Filter{}, Policy::skip, ScoreTransform::none, t2, r2);
  EXPECT_EQ(r2.rows, 2) << row;
  EXPECT_EQ(r2.skipped, 1) << row;
  EXPECT_EQ(r2.boxes, 1) << row;
  ASSERT_EQ(r2.problems.size(), 1u) << row;
  EXPECT_NE(r2.problems[0].find(file + ":2"), std::string::npos);
}

void expectRowError(const std::string& row, const std::string& cause) {
  expectReaderRowError(readAb3dmotFile, kRow0, row, cause);
}

}  // namespace

TEST(Ab3dmot, RowGeometryClassesAndScores) {
  int64_t frame = -1;
  const beslam_box3d b = parseAb3dmotRow(kRow0, "f", 1, ScoreTransform::sigmoid, frame);
  EXPECT_EQ(frame, 0);
  EXPECT_EQ(b.class_id, BESLAM_CLASS_CAR);
  EXPECT_EQ(b.track_id, -1);
  EXPECT_EQ(b.motion_state, BESLAM_MOTION_UNKNOWN);
  EXPECT_DOUBLE_EQ(b.center_cam[0], -4.5720);
  EXPECT_DOUBLE_EQ(b.center_cam[1], 1.8435 - 1.9605 / 2);  // bottom centre -> geometric centre
  EXPECT_DOUBLE_EQ(b.center_cam[2], 13.5308);
  EXPECT_DOUBLE_EQ(b.size[0], 4.7549);  // l
  EXPECT_DOUBLE_EQ(b.size[1], 1.8137);  // w
  EXPECT_DOUBLE_EQ(b.size[2], 1.9605);  // h
  EXPECT_DOUBLE_EQ(b.yaw, -2.1125);
  EXPECT_TRUE(b.flags & BESLAM_BOX_HAS_BBOX2D);
  EXPECT_FALSE(b.flags & BESLAM_BOX_HAS_VELOCITY);
  EXPECT_DOUBLE_EQ(b.bbox2d[2], 458.2292);
  EXPECT_NEAR(b.score, 1.0 / (1.0 + std::exp(-8.2981)), 1e-6);
  const beslam_box3d raw = parseAb3dmotRow(kRow1, "f", 1, ScoreTransform::none, frame);
  EXPECT_EQ(frame, 1);
  EXPECT_EQ(raw.class_id, BESLAM_CLASS_PEDESTRIAN);
  EXPECT_FLOAT_EQ(raw.score, -0.4501f);
  // Spaces instead of commas are accepted too.
  std::string spaced = kRow1;
  for (char& c : spaced) c = c == ',' ? ' ' : c;
  EXPECT_EQ(parseAb3dmotRow(spaced, "f", 1, ScoreTransform::none, frame).class_id, BESLAM_CLASS_PEDESTRIAN);
  int32_t cls = 0;
  EXPECT_TRUE(ab3dmotClass(3, cls));
  EXPECT_EQ(cls, BESLAM_CLASS_CYCLIST);
}

TEST(Ab3dmot, FileIntoFramesWithFilters) {
  TempDir dir;
  const std::string file = dir.write(
      "det.txt", "# comment\n\n" + kRow0 + "\n" + kRow1 + "\n" + "5,2,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,60,0,0\n");
  DetectionTable table;
  Report report;
  Filter filter;
  filter.min_score = 0.5;      // sigmoid(-0.45) = 0.39: the pedestrian goes
  filter.max_distance = 50.0;  // the car at 60 m goes
  readAb3dmotFile(file, filter, Policy::stop, ScoreTransform::sigmoid, table, report);
  EXPECT_EQ(report.rows, 3);
  EXPECT_EQ(report.boxes, 1);
  EXPECT_EQ(report.filtered, 2);
  EXPECT_EQ(table.lastFrame(), 5);  // frame 5 is covered even though its box was filtered
  EXPECT_EQ(table.at(0).size(), 1u);
  EXPECT_TRUE(table.at(1).empty());
  EXPECT_TRUE(table.at(3).empty());
  EXPECT_TRUE(table.at(99).empty());
  Filter cars;
  cars.classes = parseClassList("Car, Cyclist");
  DetectionTable t2;
  Report r2;
  readAb3dmotFile(file, cars, Policy::stop, ScoreTransform::sigmoid, t2, r2);
  EXPECT_EQ(r2.boxes, 2);
  EXPECT_EQ(parseClassList("all"), std::vector<int32_t>{});
  EXPECT_THROW(parseClassList("Car,Bus"), std::invalid_argument);
}

TEST(Ab3dmot, EveryMalformedRowIsReportedWithFileAndLine) {
  expectRowError("1,2,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,20,0", "expected 15 fields");
  expectRowError("1,2,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,20,0,0,7", "expected 15 fields");
  expectRowError("1,2,1,1,20,20,high,1.5,1.6,4.0,10,1.6,20,0,0", "score 'high' is not a number");
  expectRowError("1,2,1,1,20,20,3.0,1.5,1.6,nan,10,1.6,20,0,0", "l is not finite");
  expectRowError("1,2,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,inf,0,0", "z is not finite");
  expectRowError("1,2,1,1,20,20,3.0,1.5,1.6,,10,1.6,20,0,0", "l '' is not a number");
  expectRowError("1,7,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,20,0,0", "unknown class id 7");
  expectRowError("1,2.5,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,20,0,0", "class id '2.5' is not an integer");
  // Fuzz finding: a class id beyond int64 was cast unchecked (undefined behaviour).
  expectRowError("1,1e71,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,20,0,0", "class id '1e71' is not an integer class id");
  expectRowError("1,-9e18,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,20,0,0", "is not an integer class id");
  expectRowError("-1,2,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,20,0,0", "is not a frame index");
  expectRowError("1.5,2,1,1,20,20,3.0,1.5,1.6,4.0,10,1.6,20,0,0", "is not a frame index");
  expectRowError("1,2,1,1,20,20,3.0,1.5,0,4.0,10,1.6,20,0,0", "non-positive box size");
  expectRowError("1,2,1,1,20,20,3.0,-1.5,1.6,4.0,10,1.6,20,0,0", "non-positive box size");
}

TEST(Ab3dmot, MissingFileIsNamed) {
  DetectionTable table;
  Report report;
  try {
    readAb3dmotFile("/nonexistent/det.txt", Filter{}, Policy::skip, ScoreTransform::none, table, report);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/det.txt"), std::string::npos);
  }
}

TEST(KittiLabels, TrackingFileClassesDontCareAndErrors) {
  TempDir dir;
  const std::string file =
      dir.write("0000.txt",
                "0 -1 DontCare -1 -1 -10.000000 219.31 188.49 245.50 218.56 -1000 -1000 -1000 -10 -1 -1 -1\n"
                "0 0 Van 0 0 -1.793451 296.744956 161.752147 455.226042 292.372804 2.000000 1.823255 4.433886 "
                "-4.552284 1.858523 13.410495 -2.115488\n"
                "2 1 Pedestrian 0 1 0.1 700 150 740 260 1.7 0.6 0.8 2.0 1.6 9.0 0.5 0.93\n");
  DetectionTable table;
  Report report;
  readKittiTrackingFile(file, Filter{}, Policy::stop, ScoreTransform::none, table, report);
  EXPECT_EQ(report.rows, 3);
  EXPECT_EQ(report.boxes, 2);
  EXPECT_EQ(report.filtered, 1);  // DontCare
  ASSERT_EQ(table.at(0).size(), 1u);
  const beslam_box3d& van = table.at(0)[0];
  EXPECT_EQ(van.class_id, BESLAM_CLASS_VAN);
  EXPECT_EQ(van.track_id, -1);  // labels' track ids are not passed on by the replay
  EXPECT_DOUBLE_EQ(van.center_cam[1], 1.858523 - 1.0);
  EXPECT_DOUBLE_EQ(van.size[0], 4.433886);
  EXPECT_FLOAT_EQ(van.score, 1.0f);  // labels have no score
  EXPECT_FLOAT_EQ(table.at(2)[0].score, 0.93f);
  EXPECT_EQ(table.at(2)[0].occlusion, 1);

  for (const auto& [row, cause] : std::vector<std::pair<std::string, std::string>>{
           {"1 3 Bus 0 0 0.1 1 1 9 9 1.5 1.6 4.0 1 1.6 10 0", "unknown class 'Bus'"},
           {"1 3 Car 0 0 0.1 1 1 9 9 1.5 1.6 4.0 1 nan 10 0", "y 'nan' is not a number"},
           {"1 3 Car 0 0 0.1 1 1 9 9 1.5 1.6 4.0 1 1.6", "has 15 fields, expected 17 or 18"},
           {"1 3 Car 0 0 0.1 1 1 9 9 1.5 0.0 4.0 1 1.6 10 0", "non-positive box size"}}) {
    expectReaderRowError(readKittiTrackingFile, "0 0 Car 0 0 0.1 1 1 9 9 1.5 1.6 4.0 1 1.6 10 0", row, cause);
  }
}

TEST(KittiLabels, ObjectFile) {
  TempDir dir;
  const std::string file = dir.write("000003.txt",
                                     "Car 0.00 0 1.74 741.18 168.83 792.25 208.43 1.70 1.63 4.08 7.24 1.55 33.20 1.95\n"
                                     "Cyclist 0.5 2 1.74 1 1 9 9 1.70 0.63 1.8 2 1.55 12 0.1 0.77\n"
                                     "Tram 0 0 0 1 1 9 9 3.5 2.5 15 -8 1.9 40 0\n");
  DetectionTable table;
  Report report;
  readKittiObjectFile(file, 3, Filter{}, Policy::stop, ScoreTransform::none, table, report);
  ASSERT_EQ(table.at(3).size(), 3u);
  EXPECT_EQ(table.at(3)[0].class_id, BESLAM_CLASS_CAR);
  EXPECT_DOUBLE_EQ(table.at(3)[0].center_cam[1], 1.55 - 0.85);
  EXPECT_EQ(table.at(3)[1].class_id, BESLAM_CLASS_CYCLIST);
  EXPECT_FLOAT_EQ(table.at(3)[1].truncation, 0.5f);
  EXPECT_EQ(table.at(3)[2].class_id, BESLAM_CLASS_UNKNOWN);  // Tram: a KITTI class without an ABI class
  const std::string bad =
      dir.write("000004.txt", "Car 0.00 0 1.74 741.18 168.83 792.25 208.43 1.70 1.63 4.08 7.24 1.55\n");
  EXPECT_THROW(readKittiObjectFile(bad, 4, Filter{}, Policy::stop, ScoreTransform::none, table, report),
               std::exception);
}

TEST(SharedData, PointRcnnDetectionsOfAllSequences) {
  const fs::path root = fs::path(BESLAM_SHARED_DATA) / "kitti/tracking/training/det_pointrcnn";
  if (!fs::exists(root)) GTEST_SKIP() << "shared data not found: " << root;
  int64_t rows = 0, boxes = 0;
  for (const char* cls : {"Car", "Pedestrian", "Cyclist"}) {
    for (int s = 0; s <= 10; ++s) {
      char name[16];
      std::snprintf(name, sizeof name, "%04d.txt", s);
      const fs::path file = root / cls / name;
      ASSERT_TRUE(fs::exists(file)) << file;
      DetectionTable table;
      Report report;
      readAb3dmotFile(file.string(), Filter{}, Policy::stop, ScoreTransform::sigmoid, table, report);
      int64_t lines = 0;
      std::ifstream in(file);
      for (std::string l; std::getline(in, l);) lines += !l.empty();
      EXPECT_EQ(report.rows, lines) << file;
      EXPECT_EQ(report.skipped, 0) << file;
      EXPECT_EQ(report.boxes, lines) << file;
      for (int64_t f = 0; f <= table.lastFrame(); ++f)
        for (const beslam_box3d& b : table.at(f)) {
          EXPECT_GT(b.score, 0.0f);
          EXPECT_LT(b.score, 1.0f);
          EXPECT_GT(b.size[2], 0.0);
        }
      rows += report.rows, boxes += report.boxes;
    }
  }
  EXPECT_EQ(rows, boxes);
  EXPECT_GT(rows, 30000);
}

TEST(SharedData, KittiTrackingAndObjectLabels) {
  const fs::path labels = fs::path(BESLAM_SHARED_DATA) / "kitti/tracking/training/label_02/0000.txt";
  const fs::path object = fs::path(BESLAM_SHARED_DATA) / "kitti/object/training/label_2/000008.txt";
  if (!fs::exists(labels) || !fs::exists(object)) GTEST_SKIP() << "shared KITTI labels not found";
  DetectionTable table;
  Report report;
  readKittiTrackingFile(labels.string(), Filter{}, Policy::stop, ScoreTransform::none, table, report);
  EXPECT_EQ(table.lastFrame(), 153);
  EXPECT_EQ(report.skipped, 0);
  EXPECT_GT(report.boxes, 500);
  // The first Van of frame 0 (track 0): bottom centre y 1.858523, height 2.
  ASSERT_FALSE(table.at(0).empty());
  bool found = false;
  for (const beslam_box3d& b : table.at(0))
    found = found || (b.class_id == BESLAM_CLASS_VAN && std::abs(b.center_cam[1] - (1.858523 - 1.0)) < 1e-9);
  EXPECT_TRUE(found);
  DetectionTable objects;
  Report r2;
  readKittiObjectFile(object.string(), 8, Filter{}, Policy::stop, ScoreTransform::none, objects, r2);
  EXPECT_EQ(objects.at(8).size(), 6u);  // six cars, four DontCare rows filtered
  EXPECT_EQ(r2.filtered, 4);
}
