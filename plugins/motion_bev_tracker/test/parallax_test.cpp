// Parallax inside a car's 2D box on rendered frames: a textured car back (a plane facing the camera) in front of
// a forward-moving camera, parked, driving along the line of travel, oncoming, or crossing the view; and what
// the tracker makes of the measurements.
#include "beslam/motion/parallax.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "beslam/motion/bev_tracker.hpp"

using beslam::motion::BevTracker;
using beslam::motion::nearestCornerDepth;
using beslam::motion::ParallaxCheck;
using beslam::motion::ParallaxMeasurement;
using beslam::motion::ParallaxParams;
using beslam::motion::Params;

namespace {

constexpr double kF = 700, kCx = 620, kCy = 185;
constexpr int kWidth = 1240, kHeight = 370;
constexpr double kCarWidth = 1.8, kCarHeight = 1.5, kCarLength = 4.0, kCameraHeight = 1.65;

// A car's back, seen from a camera at (0, 0, ego_z) looking along +z (y down): a plane at world depth z_back
// whose face spans [x - w/2, x + w/2] x [road - h, road]. Its texture is fixed to the car.
struct Scene {
  cv::Mat texture;  // 1 px = 1 cm of the car's back
  Scene() {
    std::mt19937 rng(7);
    cv::Mat noise(static_cast<int>(kCarHeight * 100), static_cast<int>(kCarWidth * 100), CV_8UC1);
    cv::randu(noise, 0, 255);
    cv::GaussianBlur(noise, texture, cv::Size(0, 0), 2.0);
    cv::normalize(texture, texture, 0, 255, cv::NORM_MINMAX);
  }
  // The frame and the car's 2D box.
  cv::Mat render(double ego_z, double car_x, double car_z_back, cv::Rect2d& box) const {
    const double depth = car_z_back - ego_z;
    cv::Mat map_x(kHeight, kWidth, CV_32FC1), map_y(kHeight, kWidth, CV_32FC1);
    for (int v = 0; v < kHeight; ++v)
      for (int u = 0; u < kWidth; ++u) {
        const double X = (u - kCx) * depth / kF, Y = (v - kCy) * depth / kF;  // on the car's plane
        map_x.at<float>(v, u) = static_cast<float>((X - (car_x - kCarWidth / 2)) * 100);
        map_y.at<float>(v, u) = static_cast<float>((Y - (kCameraHeight - kCarHeight)) * 100);
      }
    cv::Mat image(kHeight, kWidth, CV_8UC1, cv::Scalar(90));  // a plain background: no corners of its own
    cv::remap(texture, image, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
    const double u0 = kF * (car_x - kCarWidth / 2) / depth + kCx, u1 = kF * (car_x + kCarWidth / 2) / depth + kCx;
    const double v0 = kF * (kCameraHeight - kCarHeight) / depth + kCy, v1 = kF * kCameraHeight / depth + kCy;
    box = cv::Rect2d(cv::Point2d(u0, v0), cv::Point2d(u1, v1));
    return image;
  }
};

// The lifted 3D box of a car whose back is at `depth` (heading along +z: KITTI yaw -pi/2), range off by `error`.
beslam_box3d liftedBox(int32_t track, double x, double depth, const cv::Rect2d& r, double error = 0) {
  beslam_box3d b{};
  b.class_id = BESLAM_CLASS_CAR;
  b.track_id = track;
  b.flags = BESLAM_BOX_HAS_BBOX2D;
  b.size[0] = kCarLength, b.size[1] = kCarWidth, b.size[2] = kCarHeight;
  b.yaw = -M_PI / 2;
  const double near = depth * (1 + error);
  b.center_cam[0] = x, b.center_cam[1] = kCameraHeight - kCarHeight / 2, b.center_cam[2] = near + kCarLength / 2;
  b.bbox2d[0] = r.x, b.bbox2d[1] = r.y, b.bbox2d[2] = r.x + r.width, b.bbox2d[3] = r.y + r.height;
  return b;
}

// Ten frames at 10 Hz of an ego at 9 m/s and a car starting 22 m ahead, 3 m to the right, whose back moves
// along z at car_vz and along x at car_vx. Every measurement the check makes.
std::vector<ParallaxMeasurement> drive(double car_vz, double car_vx, double lift_error = 0) {
  const Scene scene;
  ParallaxCheck check(ParallaxParams{}, kF, kF, kCx, kCy);
  std::vector<ParallaxMeasurement> all;
  for (int k = 0; k < 10; ++k) {
    const double t = 0.1 * k, ego_z = 9.0 * t, car_z = 22.0 + car_vz * t, car_x = 3.0 + car_vx * t;
    cv::Rect2d r;
    const cv::Mat image = scene.render(ego_z, car_x, car_z, r);
    Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
    T_world_cam.translation().z() = ego_z;
    const std::vector<beslam_box3d> boxes{liftedBox(5, car_x, car_z - ego_z, r, lift_error)};
    for (const ParallaxMeasurement& m : check.update(image, T_world_cam, boxes)) all.push_back(m);
  }
  return all;
}

}  // namespace

TEST(Parallax, NearestCornerOfACarSeenFromBehindIsItsBack) {
  const beslam_box3d b = liftedBox(0, 2.0, 15.0, cv::Rect2d(0, 0, 50, 50));
  EXPECT_NEAR(nearestCornerDepth(b), 15.0, 1e-9);
}

TEST(Parallax, AParkedCarIsTriangulatedAtItsOwnDepth) {
  const std::vector<ParallaxMeasurement> m = drive(0, 0);
  ASSERT_GE(m.size(), 1u);  // 9 m/s and a 3 m baseline: a measurement every four frames
  for (const ParallaxMeasurement& x : m) {
    EXPECT_EQ(x.track_id, 5);
    EXPECT_NEAR(x.depth_ratio, 1.0, 0.05);
    EXPECT_GE(x.points, 6);
  }
}

TEST(Parallax, AParkedCarWhoseBoxIsTwentyPercentFarReadsItsBoxError) {
  for (const ParallaxMeasurement& x : drive(0, 0, 0.2)) EXPECT_NEAR(x.depth_ratio, 1 / 1.2, 0.05);
}

TEST(Parallax, ACarDrivingAheadAtHalfTheEgoSpeedIsTriangulatedTwiceAsFar) {
  const std::vector<ParallaxMeasurement> m = drive(4.5, 0);
  ASSERT_GE(m.size(), 1u);
  for (const ParallaxMeasurement& x : m) EXPECT_NEAR(x.depth_ratio, 2.0, 0.2);
}

TEST(Parallax, AnOncomingCarIsTriangulatedAtHalfItsDepth) {
  const std::vector<ParallaxMeasurement> m = drive(-9.0, 0);
  ASSERT_GE(m.size(), 1u);
  for (const ParallaxMeasurement& x : m) EXPECT_NEAR(x.depth_ratio, 0.5, 0.05);
}

TEST(Parallax, ACarCrossingTheViewLeavesItsEpipolarLinesAndIsNotMeasuredStatic) {
  // 3 m/s across: its corners leave their epipolar lines, and the few that reproject give no depth near 1.
  for (const ParallaxMeasurement& x : drive(0, -3.0)) EXPECT_GT(std::abs(x.depth_ratio - 1), 0.3) << x.points;
}

TEST(Parallax, WithoutAPoseOrAnImageNothingIsMeasured) {
  ParallaxCheck check(ParallaxParams{}, kF, kF, kCx, kCy);
  const Scene scene;
  cv::Rect2d r;
  for (int k = 0; k < 10; ++k) {
    const cv::Mat image = scene.render(0.9 * k, 3.0, 22.0, r);
    const std::vector<beslam_box3d> boxes{liftedBox(1, 3.0, 22.0 - 0.9 * k, r)};
    EXPECT_TRUE(check.update(image, std::nullopt, boxes).empty());
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().z() = 0.9 * k;
    EXPECT_TRUE(check.update(cv::Mat(), T, boxes).empty());
  }
}

TEST(Parallax, BadSettingsAndIntrinsicsAreRefused) {
  ParallaxParams p;
  p.depth_quantile = 2;
  EXPECT_THROW(ParallaxCheck(p, kF, kF, kCx, kCy), std::invalid_argument);
  EXPECT_THROW(ParallaxCheck(ParallaxParams{}, 0, kF, kCx, kCy), std::invalid_argument);
  Params tracker;
  tracker.parallax = true;
  tracker.parallax_check.min_points = 1;
  EXPECT_FALSE(tracker.validate().empty());
  tracker.parallax_check.min_points = 6;
  tracker.parallax_tolerance = 1.5;
  EXPECT_FALSE(tracker.validate().empty());
}

TEST(Parallax, TheTrackerCallsAnUndecidedTrackStaticOnlyWithinTheTolerance) {
  Params p;
  p.parallax = true;
  BevTracker tracker(p);
  beslam_box3d box{};
  box.class_id = BESLAM_CLASS_CAR;
  box.size[0] = 4, box.size[1] = 1.8, box.size[2] = 1.5;
  box.center_cam[1] = 0.9, box.center_cam[2] = 15;
  const std::vector<beslam::motion::Decision> d =
      tracker.update(0.0, Eigen::Isometry3d::Identity(), std::vector<beslam_box3d>{box});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].motion_state, BESLAM_MOTION_UNKNOWN);
  EXPECT_EQ(tracker.parallaxEvidence(d[0].track_id, 1.45), BESLAM_MOTION_UNKNOWN);  // 45 % off: no evidence
  EXPECT_EQ(tracker.parallaxEvidence(d[0].track_id, 0.8), BESLAM_MOTION_STATIC);
  EXPECT_FALSE(tracker.parallaxEvidence(d[0].track_id + 100, 1.0).has_value());
}

namespace {

// One car box 15 m ahead (camera frame), with its image box.
beslam_box3d carBox(double x, double z, const Eigen::Vector4d& box2d, bool uncertain = false) {
  beslam_box3d b{};
  b.class_id = BESLAM_CLASS_CAR;
  b.track_id = -1;
  b.flags = BESLAM_BOX_HAS_BBOX2D | (uncertain ? BESLAM_BOX_UNCERTAIN : 0u);
  b.size[0] = 4, b.size[1] = 1.8, b.size[2] = 1.5;
  b.center_cam[0] = x, b.center_cam[1] = 0.9, b.center_cam[2] = z;
  for (int i = 0; i < 4; ++i) b.bbox2d[i] = box2d[i];
  return b;
}

}  // namespace

TEST(Parallax, ACutBoxStaysOnItsTrackByItsImageBoxWhenItsLiftJumps) {
  Params p;
  p.uncertain_evidence = false;
  BevTracker tracker(p);
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  const auto first = tracker.update(0.0, I, {carBox(3, 15, {900, 150, 1100, 250})});
  ASSERT_GE(first[0].track_id, 0);
  // Cut by the border: the lift puts what is visible 6 m away, but the image box overlaps the last one.
  const auto cut = tracker.update(0.1, I, {carBox(6, 21, {950, 152, 1240, 255}, true)});
  EXPECT_EQ(cut[0].track_id, first[0].track_id);
  // A cut box that overlaps no track's last image box starts nothing.
  const auto other = tracker.update(0.2, I, {carBox(-6, 21, {0, 152, 100, 255}, true)});
  EXPECT_EQ(other[0].track_id, -1);
}

TEST(Parallax, AFreshMeasurementOutranksTheLiftedBoxesSpeedUntilOneDisagrees) {
  // A parked car whose lifted boxes drift at 2 m/s (a range error changing as the camera closes in): without
  // parallax it is called dynamic; with a measurement within the tolerance every fourth frame it stays static
  // until one says its depth is off by half, after which the boxes' speed turns it dynamic again.
  auto run = [](bool with_parallax, int disagree_from) {
    Params p;
    p.parallax = with_parallax;
    BevTracker tracker(p);
    int32_t state = BESLAM_MOTION_UNKNOWN, id = -1;
    std::vector<int32_t> states;
    for (int k = 0; k < 40; ++k) {
      const double t = 0.1 * k;
      const auto d = tracker.update(t, Eigen::Isometry3d::Identity(), {carBox(3, 15 + 2.0 * t, {900, 150, 1000, 220})});
      id = d[0].track_id;
      state = d[0].motion_state;
      if (with_parallax && k % 4 == 3) {
        const auto s = tracker.parallaxEvidence(id, k >= disagree_from ? 1.5 : 1.05);
        if (s) state = *s;
      }
      states.push_back(state);
    }
    return states;
  };
  const std::vector<int32_t> plain = run(false, 1000);
  EXPECT_EQ(plain.back(), BESLAM_MOTION_DYNAMIC);
  const std::vector<int32_t> held = run(true, 1000);
  int static_frames = 0;
  for (size_t k = 4; k < held.size(); ++k) static_frames += held[k] == BESLAM_MOTION_STATIC;
  EXPECT_EQ(held.back(), BESLAM_MOTION_STATIC);
  EXPECT_GE(static_frames, 30);
  const std::vector<int32_t> released = run(true, 20);
  EXPECT_EQ(released.back(), BESLAM_MOTION_DYNAMIC);
}
