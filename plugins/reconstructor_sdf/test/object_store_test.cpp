// ObjectStore: association by track id, what each keyframe adds (boxes, labelled map points, LiDAR returns
// inside the box above the road), objects ended by a dynamic call, bounded LiDAR memory, the box consensus,
// observations that follow their keyframes; silhouettes sampled from a label mask and kept per object.
#include "objects/object_store.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "beslam/sdk/views.hpp"
#include "objects/mask_silhouettes.hpp"

namespace beslam::recon {
namespace {

// A parked car 10 m ahead (geometric centre), heading along camera +x.
beslam_box3d carBox(int32_t track, int32_t state, double z = 10.0, double yaw = 0.0) {
  beslam_box3d b = sdk::newBox();
  b.class_id = BESLAM_CLASS_CAR;
  b.track_id = track;
  b.motion_state = state;
  b.center_cam[0] = 2, b.center_cam[1] = 0.9, b.center_cam[2] = z;
  b.size[0] = 4.4, b.size[1] = 1.8, b.size[2] = 1.5;
  b.yaw = yaw;
  return b;
}

KeyframeInput keyframe(int64_t id, const std::vector<beslam_box3d>& boxes) {
  KeyframeInput in;
  in.keyframe_id = id;
  in.frame_index = 10 * id;
  in.T_world_cam.translation() = Eigen::Vector3d(0, 0, double(id));  // 1 m forward a keyframe
  in.boxes = &boxes;
  return in;
}

TEST(ObjectStore, AssociatesByTrackIdAndCollectsLabelledPoints) {
  ObjectStore store(StoreOptions{});
  const std::vector<beslam_box3d> boxes = {carBox(3, BESLAM_MOTION_STATIC), carBox(4, BESLAM_MOTION_UNKNOWN),
                                           carBox(-1, BESLAM_MOTION_STATIC)};
  KeyframeInput in = keyframe(0, boxes);
  in.points = {{11, {2, 1, 10}, BESLAM_LABEL_STATIC_BASE + 3},
               {12, {2, 1, 11}, BESLAM_LABEL_STATIC_BASE + 4},
               {13, {0, 0, 30}, BESLAM_LABEL_BACKGROUND}};
  std::vector<int32_t> ended;
  EXPECT_EQ(store.observe(in, ended), std::set<int32_t>{3});  // unknown motion and no track id add nothing
  const std::vector<beslam_box3d> closer = {carBox(3, BESLAM_MOTION_STATIC, 9.0)};  // the camera moved 1 m
  KeyframeInput again = keyframe(1, closer);
  again.points = {{11, {2, 1, 10.5}, BESLAM_LABEL_STATIC_BASE + 3},
                  {14, {2, 0.5, 9}, BESLAM_LABEL_STATIC_BASE + 3},
                  {15, {2, 1, 13}, BESLAM_LABEL_STATIC_BASE + 3}};  // mask bleed: 3 m behind the car
  store.observe(again, ended);
  const ObjectRecord* o = store.find(3);
  ASSERT_NE(o, nullptr);
  EXPECT_EQ(o->boxes.size(), 2u);
  ASSERT_EQ(o->map_points.size(), 3u);  // point 11 once, at its latest position
  EXPECT_NEAR(o->map_points.at(11).p_world().z(), 10.5, 1e-12);
  EXPECT_EQ(o->surfaceObservations(0.5).size(), 2u);  // no LiDAR: the map points in the box, not 15
  EXPECT_EQ(o->surfaceObservations(5.0).size(), 3u);
  EXPECT_TRUE(ended.empty());
  EXPECT_EQ(store.find(4), nullptr);
}

TEST(ObjectStore, ADynamicCallEndsTheObject) {
  ObjectStore store(StoreOptions{});
  std::vector<int32_t> ended;
  const std::vector<beslam_box3d> parked = {carBox(5, BESLAM_MOTION_STATIC)};
  store.observe(keyframe(0, parked), ended);
  const std::vector<beslam_box3d> moving = {carBox(5, BESLAM_MOTION_DYNAMIC), carBox(6, BESLAM_MOTION_DYNAMIC)};
  EXPECT_TRUE(store.observe(keyframe(1, moving), ended).empty());
  EXPECT_EQ(ended, std::vector<int32_t>{5});  // 6 was never an object
  EXPECT_EQ(store.find(5), nullptr);
}

TEST(ObjectStore, FarBoxesAndOtherClassesAddNothing) {
  StoreOptions options;
  options.max_range = 20;
  ObjectStore store(options);
  beslam_box3d person = carBox(8, BESLAM_MOTION_STATIC);
  person.class_id = BESLAM_CLASS_PEDESTRIAN;
  const std::vector<beslam_box3d> boxes = {carBox(7, BESLAM_MOTION_STATIC, 35.0), person};
  std::vector<int32_t> ended;
  EXPECT_TRUE(store.observe(keyframe(0, boxes), ended).empty());
}

TEST(ObjectStore, LidarReturnsInsideTheBoxAboveTheRoadInTheWorldFrame) {
  StoreOptions options;
  options.max_lidar_points = 100;
  ObjectStore store(options);
  const std::vector<beslam_box3d> boxes = {carBox(2, BESLAM_MOTION_STATIC)};
  KeyframeInput in = keyframe(3, boxes);
  // The box spans x 2 +- 2.2, y 0.9 +- 0.75 (y down: the road is at y = 1.65), z 10 +- 0.9.
  in.lidar_cam = {{2, 0.5, 9.2},   // on the car's side
                  {3.5, 1.0, 10},  // inside
                  {2, 1.62, 10},   // road under the car
                  {2, 0.5, 12.5},  // behind the car
                  {9, 0.5, 10}};   // beside it
  std::vector<int32_t> ended;
  store.observe(in, ended);
  const ObjectRecord* o = store.find(2);
  ASSERT_NE(o, nullptr);
  ASSERT_EQ(o->lidarPointCount(), 2u);
  EXPECT_NEAR(o->lidarPoints()[0].z(), 12.2, 1e-9);  // camera 3 m along world z
  EXPECT_EQ(o->surfaceObservations(0.5).size(), 2u);
  // Over the cap, every k-th return is kept.
  for (int i = 0; i < 300; ++i) in.lidar_cam.push_back({2.0 + 0.001 * i, 0.5, 9.2});
  store.observe(in, ended);
  EXPECT_LE(static_cast<int>(store.find(2)->lidarPointCount()), options.max_lidar_points);
  EXPECT_GT(static_cast<int>(store.find(2)->lidarPointCount()), options.max_lidar_points / 2);
}

TEST(ObjectStore, BoxConsensusIsRobustToOneBadBoxAndToAFlippedHeading) {
  ObjectStore store(StoreOptions{});
  std::vector<int32_t> ended;
  for (int k = 0; k < 5; ++k) {
    // The camera moves 1 m a keyframe: the box's z in the camera shrinks by 1 so the car stays put.
    double yaw = k == 2 ? M_PI : 0.05;         // one detection faces the other way
    double z = 10.0 - k + (k == 4 ? 3.0 : 0);  // one is 3 m off
    const std::vector<beslam_box3d> boxes = {carBox(1, BESLAM_MOTION_STATIC, z, yaw)};
    store.observe(keyframe(k, boxes), ended);
  }
  const ObjectRecord* o = store.find(1);
  const Eigen::Isometry3d T = o->boxPose();
  EXPECT_NEAR(T.translation().z(), 10.0, 1e-9);  // the median ignores the 3 m outlier
  EXPECT_NEAR(T.translation().x(), 2.0, 1e-9);
  // Heading along camera x (world x here), up along -y: the flipped box does not turn the average.
  EXPECT_GT(std::abs(T.linear().col(0).x()), 0.99);
  EXPECT_NEAR(T.linear().col(2).y(), -1.0, 1e-9);
  EXPECT_NEAR(o->boxSize().x(), 4.4, 1e-9);
}

// Boxes and LiDAR returns stay with the keyframe that made them: when the backend moves its keyframes (a
// loop correction, local BA), the next fit sees them where the keyframes are now; a keyframe the backend
// no longer lists keeps its last pose.
TEST(ObjectStore, ObservationsFollowTheirKeyframes) {
  ObjectStore store(StoreOptions{});
  std::vector<int32_t> ended;
  const std::vector<beslam_box3d> boxes = {carBox(1, BESLAM_MOTION_STATIC)};
  for (int k = 0; k < 3; ++k) {
    KeyframeInput in = keyframe(k, boxes);
    in.lidar_cam = {{2, 0.5, 9.2}};
    in.points = {{20 + k, {2, 1, 10}, BESLAM_LABEL_STATIC_BASE + 1}};  // one map point each
    store.observe(in, ended);
  }
  // Keyframes 0 and 1 (frames 0 and 10) shifted 0.5 m along world x; keyframe 2 (frame 20) is gone.
  std::map<int64_t, Eigen::Isometry3d> now;
  for (int64_t frame : {0, 10}) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(0.5, 0, double(frame / 10));
    now[frame] = T;
  }
  store.followKeyframes(now);
  const ObjectRecord* o = store.find(1);
  ASSERT_NE(o, nullptr);
  ASSERT_EQ(o->boxes.size(), 3u);
  EXPECT_NEAR(o->boxes[0].T_world_obj().translation().x(), 2.5, 1e-12);
  EXPECT_NEAR(o->boxes[1].T_world_obj().translation().x(), 2.5, 1e-12);
  EXPECT_NEAR(o->boxes[2].T_world_obj().translation().x(), 2.0, 1e-12);  // its last known pose
  EXPECT_NEAR(o->boxPose().translation().x(), 2.5, 1e-12);               // the median of 2.5, 2.5, 2.0
  const std::vector<Eigen::Vector3d> lidar = o->lidarPoints();
  ASSERT_EQ(lidar.size(), 3u);
  EXPECT_NEAR(lidar[0].x(), 2.5, 1e-12);
  EXPECT_NEAR(lidar[2].x(), 2.0, 1e-12);
  EXPECT_NEAR(lidar[1].z(), 10.2, 1e-12);  // keyframe 1: 1 m along world z, the return 9.2 m ahead
  ASSERT_EQ(o->map_points.size(), 3u);
  EXPECT_NEAR(o->map_points.at(21).p_world().x(), 2.5, 1e-12);
  EXPECT_NEAR(o->map_points.at(22).p_world().x(), 2.0, 1e-12);
  EXPECT_EQ(o->surfaceObservations(0.5).size(), 3u);  // LiDAR first
  store.followKeyframes({});                          // nothing given (an older host): nothing moves
  EXPECT_NEAR(store.find(1)->boxPose().translation().x(), 2.5, 1e-12);
  Eigen::Isometry3d broken = Eigen::Isometry3d::Identity();
  broken.translation().x() = std::numeric_limits<double>::quiet_NaN();
  store.followKeyframes({{0, broken}, {10, broken}});  // a non-finite pose moves nothing
  EXPECT_NEAR(store.find(1)->boxPose().translation().x(), 2.5, 1e-12);
}

TEST(MaskSilhouettes, MaskPixelsMeetTheCarBackgroundBesideItPassesItOthersAreLeftOut) {
  beslam_camera camera{};
  camera.width = 200, camera.height = 100, camera.fx = camera.fy = 100, camera.cx = 100, camera.cy = 50;
  cv::Mat mask(100, 200, CV_16UC1, cv::Scalar(BESLAM_LABEL_BACKGROUND));
  mask(cv::Rect(80, 40, 40, 20)).setTo(BESLAM_LABEL_STATIC_BASE + 7);  // the car
  mask(cv::Rect(115, 40, 30, 20)).setTo(BESLAM_LABEL_DYNAMIC);         // a moving car in front of its right end
  const std::vector<beslam_box3d> boxes = {carBox(7, BESLAM_MOTION_STATIC), carBox(9, BESLAM_MOTION_STATIC)};
  const auto samples = sampleSilhouettes(mask, camera, boxes, 8);
  ASSERT_EQ(samples.size(), 1u);  // track 9 has no pixel in the mask
  const SilhouetteSample& s = samples.at(7);
  ASSERT_EQ(s.u_cam.size(), s.inside.size());
  int inside = 0, outside = 0;
  for (size_t i = 0; i < s.u_cam.size(); ++i) {
    EXPECT_NEAR(s.u_cam[i].norm(), 1.0, 1e-12);
    const double x = camera.fx * s.u_cam[i].x() / s.u_cam[i].z() + camera.cx;
    const double y = camera.fy * s.u_cam[i].y() / s.u_cam[i].z() + camera.cy;
    const int xi = static_cast<int>(std::lround(x)), yi = static_cast<int>(std::lround(y));
    // The lattice spans the car's pixels (35 x 20: the moving car owns the rest) grown by a quarter a side.
    EXPECT_GE(xi, 80 - 9);
    EXPECT_LT(xi, 115 + 9);
    EXPECT_GE(yi, 40 - 5);
    EXPECT_LT(yi, 60 + 5);
    const uint16_t label = mask.at<uint16_t>(yi, xi);
    EXPECT_NE(label, BESLAM_LABEL_DYNAMIC);  // another object's pixels give no ray
    EXPECT_EQ(s.inside[i] != 0, label == BESLAM_LABEL_STATIC_BASE + 7);
    (s.inside[i] ? inside : outside) += 1;
  }
  EXPECT_GE(inside, 16);
  EXPECT_GE(outside, 16);
  EXPECT_LT(s.u_cam.size(), 64u);  // the moving car's pixels were left out
  // A mask of another size or type, or a lattice under 2, samples nothing.
  EXPECT_TRUE(sampleSilhouettes(cv::Mat(50, 100, CV_16UC1, cv::Scalar(0)), camera, boxes, 8).empty());
  EXPECT_TRUE(sampleSilhouettes(cv::Mat(100, 200, CV_8UC1, cv::Scalar(0)), camera, boxes, 8).empty());
  EXPECT_TRUE(sampleSilhouettes(mask, camera, boxes, 1).empty());
}

TEST(ObjectStore, KeepsTheNewestSilhouettesOfAStaticCarWhereTheirKeyframesAre) {
  StoreOptions options;
  options.silhouette_keyframes = 2;
  ObjectStore store(options);
  std::vector<int32_t> ended;
  const std::vector<beslam_box3d> boxes = {carBox(3, BESLAM_MOTION_STATIC), carBox(4, BESLAM_MOTION_UNKNOWN)};
  for (int k = 0; k < 3; ++k) {
    KeyframeInput in = keyframe(k, boxes);
    SilhouetteSample sample;
    sample.u_cam = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.6, 0, 0.8)};
    sample.inside = {1, 0};
    in.silhouettes[3] = sample;
    in.silhouettes[4] = sample;  // unknown motion: not kept
    store.observe(in, ended);
  }
  ASSERT_EQ(store.find(4), nullptr);
  const ObjectRecord* o = store.find(3);
  ASSERT_NE(o, nullptr);
  ASSERT_EQ(o->silhouettes.size(), 2u);  // the newest two keyframes
  EXPECT_EQ(o->silhouettes.front().frame_index, 10);
  std::vector<WorldSilhouetteRay> rays = o->silhouetteRays();
  ASSERT_EQ(rays.size(), 4u);
  EXPECT_TRUE(rays[0].inside);
  EXPECT_FALSE(rays[1].inside);
  EXPECT_NEAR((rays[0].origin_world - Eigen::Vector3d(0, 0, 1)).norm(), 0, 1e-12);
  // The keyframe at frame 10 moves 0.5 m left and turns 90 degrees: its rays go with it.
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  moved.translation() = Eigen::Vector3d(-0.5, 0, 1);
  store.followKeyframes({{10, moved}});
  rays = store.find(3)->silhouetteRays();
  EXPECT_NEAR((rays[0].origin_world - Eigen::Vector3d(-0.5, 0, 1)).norm(), 0, 1e-12);
  EXPECT_NEAR((rays[0].direction_world - Eigen::Vector3d(1, 0, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR((rays[2].origin_world - Eigen::Vector3d(0, 0, 2)).norm(), 0, 1e-12);  // frame 20 unchanged
}

}  // namespace
}  // namespace beslam::recon
