#include "beslam/static_map/static_map.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "beslam/common/error.hpp"
#include "beslam/static_map/score.hpp"

namespace fs = std::filesystem;

namespace beslam::static_map {
namespace {

beslam_box3d box(double x, double y, double z, int32_t state) {
  beslam_box3d b{};
  b.center_cam[0] = x, b.center_cam[1] = y, b.center_cam[2] = z;
  b.size[0] = 4.0, b.size[1] = 1.8, b.size[2] = 1.5;  // l w h
  b.motion_state = state;
  return b;
}

// A wall at z = 12 m (x -3..3, y -1..1) and a car-sized cluster at z = 6 m, as LiDAR points (LiDAR frame =
// camera frame here).
std::vector<float> scene() {
  std::vector<float> xyzi;
  auto add = [&](double x, double y, double z) { xyzi.insert(xyzi.end(), {float(x), float(y), float(z), 1.f}); };
  for (double x = -3; x <= 3; x += 0.05)
    for (double y = -1; y <= 1; y += 0.05) add(x, y, 12);
  for (double x = -1.5; x <= 1.5; x += 0.05)
    for (double y = -0.6; y <= 0.6; y += 0.05) add(x, y, 5.1);  // the car's rear face
  return xyzi;
}

bool occupied(const octomap::OcTree& tree, double x, double y, double z) {
  const octomap::OcTreeNode* n = tree.search(x, y, z);
  return n && tree.isNodeOccupied(n);
}

TEST(InsideBox, GrowsByTheMarginAndFollowsYaw) {
  beslam_box3d b = box(0, 0, 10, BESLAM_MOTION_DYNAMIC);
  EXPECT_TRUE(insideBox(b, {1.9, 0, 10}, 0));
  EXPECT_FALSE(insideBox(b, {2.1, 0, 10}, 0));
  EXPECT_TRUE(insideBox(b, {2.1, 0, 10}, 0.2));
  b.yaw = M_PI / 2;  // length now along the camera z axis
  EXPECT_FALSE(insideBox(b, {1.9, 0, 10}, 0));
  EXPECT_TRUE(insideBox(b, {0, 0, 11.9}, 0));
}

TEST(StaticMapBuilder, MovingCarsLeaveNoVoxelsParkedOnesDo) {
  const std::vector<float> xyzi = scene();
  for (int32_t state : {BESLAM_MOTION_DYNAMIC, BESLAM_MOTION_UNKNOWN, BESLAM_MOTION_STATIC}) {
    StaticMapBuilder builder(Options{});
    builder.addScan(0, xyzi.data(), xyzi.size() / 4, 4 * sizeof(float), Eigen::Isometry3d::Identity(),
                    {box(0, 0, 6, state)});
    const auto tree = builder.build({{0, Eigen::Isometry3d::Identity()}}, {}, {});
    EXPECT_TRUE(occupied(*tree, 0, 0, 12.05)) << "the wall";
    EXPECT_EQ(occupied(*tree, 0, 0, 5.1), state == BESLAM_MOTION_STATIC) << "the car, state " << state;
    const octomap::OcTreeNode* free = tree->search(0.0, 0.0, 3.0);
    ASSERT_NE(free, nullptr) << "space the rays crossed is known";
    EXPECT_FALSE(tree->isNodeOccupied(free));
    EXPECT_EQ(builder.stats().scans, 1);
    EXPECT_EQ(builder.stats().points_in_boxes > 0, state != BESLAM_MOTION_STATIC);
  }
}

TEST(StaticMapBuilder, ReturnsOutsideTheCameraViewAreCut) {
  Options options;
  options.camera.width = 200, options.camera.height = 100;
  options.camera.fx = options.camera.fy = 100, options.camera.cx = 100, options.camera.cy = 50;
  std::vector<float> xyzi = {0, 0, 10, 1, 0, 0, -10, 1, 30, 0, 10, 1};  // ahead, behind, far to the side
  StaticMapBuilder builder(options);
  builder.addScan(0, xyzi.data(), 3, 4 * sizeof(float), Eigen::Isometry3d::Identity(), {});
  const auto tree = builder.build({{0, Eigen::Isometry3d::Identity()}}, {}, {});
  EXPECT_TRUE(occupied(*tree, 0, 0, 10.05));
  EXPECT_FALSE(occupied(*tree, 0, 0, -10.05));
  EXPECT_FALSE(occupied(*tree, 30.05, 0, 10.05));
  EXPECT_EQ(builder.stats().points_outside_view, 2);
}

TEST(StaticMapBuilder, ScansGoWhereTheFinalPoseSaysAndUnposedFramesAreSkipped) {
  const std::vector<float> xyzi = scene();
  StaticMapBuilder builder(Options{});
  builder.addScan(3, xyzi.data(), xyzi.size() / 4, 4 * sizeof(float), Eigen::Isometry3d::Identity(), {});
  builder.addScan(4, xyzi.data(), xyzi.size() / 4, 4 * sizeof(float), Eigen::Isometry3d::Identity(), {});
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  T_world_cam.translation() = Eigen::Vector3d(100, 0, 0);
  const auto tree = builder.build({{3, T_world_cam}}, {}, {});
  EXPECT_TRUE(occupied(*tree, 100, 0, 12.05));
  EXPECT_FALSE(occupied(*tree, 0, 0, 12.05));
  EXPECT_EQ(builder.stats().scans, 1);
}

TEST(StaticMapBuilder, MapPointsInsideMovingBoxesAreDropped) {
  StaticMapBuilder builder(Options{});
  builder.addBoxes(7, {box(0, 0, 6, BESLAM_MOTION_DYNAMIC)});
  builder.addBoxes(8, {box(5, 0, 6, BESLAM_MOTION_STATIC)});  // all static: not kept
  const std::vector<Eigen::Vector3d> points = {{0, 0, 6}, {0, 0, 20}, {5, 0, 6}};
  const auto tree = builder.build({{7, Eigen::Isometry3d::Identity()}, {8, Eigen::Isometry3d::Identity()}}, points,
                                  {Eigen::Vector3d::Zero()});
  EXPECT_FALSE(occupied(*tree, 0, 0, 6));
  EXPECT_TRUE(occupied(*tree, 0, 0, 20));
  EXPECT_TRUE(occupied(*tree, 5, 0, 6));
  EXPECT_EQ(builder.stats().map_points, 2);
  EXPECT_EQ(builder.stats().points_in_boxes, 1);
}

class TreeFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("beslam_static_map_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(TreeFiles, RoundTripAndBadFilesNamed) {
  octomap::OcTree tree(0.2);
  tree.updateNode(octomap::point3d(1, 2, 3), true);
  const std::string path = (dir_ / "map.bt").string();
  writeTree(tree, path);
  const auto back = readTree(path);
  EXPECT_DOUBLE_EQ(back->getResolution(), 0.2);
  EXPECT_TRUE(occupied(*back, 1, 2, 3));

  std::ofstream(dir_ / "junk.bt") << "not a tree\n";
  try {
    readTree((dir_ / "junk.bt").string());
    FAIL() << "junk accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("junk.bt"), std::string::npos) << e.what();
  }
  {  // truncated: the header and half the data
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(dir_ / "cut.bt", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  EXPECT_THROW(readTree((dir_ / "cut.bt").string()), Error);
  EXPECT_THROW(readTree((dir_ / "missing.bt").string()), Error);
}

// Truth: one car drives along z at x = 0 (frames 0-2, moving), one stands at x = 5; the ego stands still.
TEST_F(TreeFiles, ScoreCountsVoxelsInMovingPathsAndParkedCars) {
  const fs::path seq = dir_ / "sequences" / "00";
  fs::create_directories(seq / "label_02");
  fs::create_directories(dir_ / "poses");
  {
    std::ofstream labels(seq / "label_02" / "00.txt"), motion(seq / "objects_motion.txt"),
        poses(dir_ / "poses" / "00.txt");
    for (int f = 0; f < 3; ++f) {
      // frame track type trunc occl alpha x1 y1 x2 y2 h w l x y z ry (bottom centre, y down)
      labels << f << " 1 Car 0 0 0 0 0 10 10 1.5 1.8 4.0 0 0.75 " << 10 + 5 * f << " 1.5707963\n";
      labels << f << " 2 Car 0 0 0 0 0 10 10 1.5 1.8 4.0 5 0.75 10 1.5707963\n";
      motion << f << " 1 1 5.0\n" << f << " 2 0 0.0\n";
      poses << "1 0 0 0 0 1 0 0 0 0 1 0\n";
    }
  }
  octomap::OcTree tree(0.2);
  tree.updateNode(octomap::point3d(0.1f, 0.1f, 15.1f), true);   // in the moving car's path (frame 1)
  tree.updateNode(octomap::point3d(5.1f, 0.1f, 10.1f), true);   // in the parked car
  tree.updateNode(octomap::point3d(-6.1f, 0.1f, 10.1f), true);  // elsewhere
  const MapScore s = scoreStaticMap(tree, seq.string(), "00", Similarity{});
  EXPECT_EQ(s.occupied, 3);
  EXPECT_EQ(s.in_moving_paths, 1);
  EXPECT_EQ(s.in_parked_cars, 1);
  EXPECT_EQ(s.parked_cars, 1);
  EXPECT_EQ(s.parked_cars_mapped, 1);
  Similarity shift;  // the map 30 m off: nothing lands in a box
  shift.t = Eigen::Vector3d(30, 0, 0);
  const MapScore moved = scoreStaticMap(tree, seq.string(), "00", shift);
  EXPECT_EQ(moved.in_moving_paths + moved.in_parked_cars, 0);
  EXPECT_THROW(scoreStaticMap(tree, (dir_ / "nowhere").string(), "00", Similarity{}), Error);
}

}  // namespace
}  // namespace beslam::static_map
