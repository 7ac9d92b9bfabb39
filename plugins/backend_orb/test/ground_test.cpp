// Ground plane and ground-height prior on simulated geometry: the fit finds the road under a pitched
// camera among walls and a car's hood, refuses too few points and a steep ramp, and pools the road points
// of neighbouring keyframes; the reference is a
// median; local BA with the prior pulls a map whose scale is free (only the origin fixed) back to the
// reference height, where plain BA leaves the scale where it was.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "ground/ground_plane.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "map_builder.hpp"
#include "optimize/bundle_adjustment.hpp"

namespace beslam::orb {
namespace {

const Camera kCam{1226, 370, 718.856, 718.856, 607.19, 185.22};
constexpr double kHeight = 1.6;  // camera above the road (world y points down, road at y = kHeight)

std::vector<Eigen::Vector3d> roadPoints(int n, std::mt19937& rng, double height_noise) {
  std::uniform_real_distribution<double> ux(-6, 6), uz(5, 30);
  std::normal_distribution<double> dy(0, height_noise);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < n; ++i) p.emplace_back(ux(rng), kHeight + dy(rng), uz(rng));
  return p;
}

// Walls on both sides and a car hood 0.7 m above the road: points that are not the road.
std::vector<Eigen::Vector3d> clutter(std::mt19937& rng) {
  std::uniform_real_distribution<double> wy(-3, 1.4), wz(5, 30), hx(2, 4), hz(8, 12);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 60; ++i) p.emplace_back(i % 2 ? 5.0 : -5.0, wy(rng), wz(rng));
  for (int i = 0; i < 30; ++i) p.emplace_back(hx(rng), kHeight - 0.7, hz(rng));
  return p;
}

KeyFrame* singleKeyFrame(Map& map, const ScalePyramid& pyr, const Eigen::Isometry3d& T_cw,
                         const std::vector<Eigen::Vector3d>& points) {
  return test::buildMap(map, kCam, pyr, {T_cw}, {T_cw}, points, points, 0.0, 1).front();
}

double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

TEST(GroundPlane, FindsTheRoadUnderAPitchedCameraAmongWallsAndACarHood) {
  std::mt19937 rng(3);
  auto points = roadPoints(80, rng, 0.01);
  const auto other = clutter(rng);
  points.insert(points.end(), other.begin(), other.end());
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  T_wc.linear() = Eigen::AngleAxisd(3.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();  // looks down
  const Eigen::Isometry3d T_cw = T_wc.inverse();
  const ScalePyramid pyr(8, 1.2);
  Map map;
  KeyFrame* kf = singleKeyFrame(map, pyr, T_cw, points);

  const auto plane = fitGroundPlane(*kf, GroundPlaneOptions{}, Eigen::Vector3d::UnitY(), 20.0);
  ASSERT_TRUE(plane.has_value());
  EXPECT_NEAR(plane->height, kHeight, 0.02 * kHeight);
  const Eigen::Vector3d n_expected = T_cw.linear() * Eigen::Vector3d::UnitY();
  EXPECT_LT(angleDeg(plane->normal_cam, n_expected), 0.5);
  EXPECT_GE(plane->inliers.size(), 70u);
  for (MapPoint* mp : plane->inliers) EXPECT_NEAR(mp->position.y(), kHeight, 0.06) << "a non-road point is an inlier";

  // The same keyframe gives the same plane (seeded by the keyframe).
  const auto again = fitGroundPlane(*kf, GroundPlaneOptions{}, Eigen::Vector3d::UnitY(), 20.0);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->height, plane->height);
  EXPECT_EQ(again->inliers, plane->inliers);
}

TEST(GroundPlane, TooFewRoadPointsGiveNoPlane) {
  std::mt19937 rng(4);
  auto points = roadPoints(GroundPlaneOptions{}.min_inliers - 5, rng, 0.005);
  const auto other = clutter(rng);
  points.insert(points.end(), other.begin(), other.begin() + 60);  // the walls only
  const ScalePyramid pyr(8, 1.2);
  Map map;
  KeyFrame* kf = singleKeyFrame(map, pyr, Eigen::Isometry3d::Identity(), points);
  EXPECT_FALSE(fitGroundPlane(*kf, GroundPlaneOptions{}, Eigen::Vector3d::UnitY(), 20.0).has_value());
}

TEST(GroundPlane, ASteepRampIsNotTheGround) {
  std::mt19937 rng(5);
  auto points = roadPoints(80, rng, 0.005);
  // Tilt the whole road by 30 degrees about the camera's z axis (a ramp or a wall-like slope).
  const Eigen::Matrix3d R = Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (auto& p : points) p = R * p;
  const ScalePyramid pyr(8, 1.2);
  Map map;
  KeyFrame* kf = singleKeyFrame(map, pyr, Eigen::Isometry3d::Identity(), points);
  EXPECT_FALSE(fitGroundPlane(*kf, GroundPlaneOptions{}, Eigen::Vector3d::UnitY(), 20.0).has_value());
  EXPECT_TRUE(fitGroundPlane(*kf, GroundPlaneOptions{}, Eigen::Vector3d::UnitY(), 35.0).has_value());
}

TEST(GroundPlane, AKeyFrameWithFewRoadPointsOfItsOwnFitsItWithItsNeighboursRoad) {
  std::mt19937 rng(6);
  const int n = GroundPlaneOptions{}.min_inliers - 10;  // too few road points for any keyframe alone
  const auto road_a = roadPoints(n, rng, 0.005), road_b = roadPoints(n, rng, 0.005);
  auto points = clutter(rng);
  points.resize(60);  // the walls, seen by every keyframe: they make them covisible
  const size_t first_a = points.size(), first_b = first_a + road_a.size();
  points.insert(points.end(), road_a.begin(), road_a.end());
  points.insert(points.end(), road_b.begin(), road_b.end());
  std::vector<Eigen::Isometry3d> T_cw(6, Eigen::Isometry3d::Identity());  // 0.5 m apart down the road
  for (size_t k = 0; k < T_cw.size(); ++k) T_cw[k].translation() = Eigen::Vector3d(0, 0, -0.5 * k);
  const ScalePyramid pyr(8, 1.2);
  Map map;
  const auto kfs = test::buildMap(map, kCam, pyr, T_cw, T_cw, points, points, 0.0, 1);
  // Keyframes 0-2 see only road a, keyframes 3-5 only road b (three observations each stay).
  auto unsee = [&](KeyFrame* kf, size_t from, size_t to) {
    for (size_t i = from; i < to; ++i) {
      kf->points[i]->eraseObservation(kf);
      kf->erasePoint(i);
    }
  };
  for (int k = 0; k < 3; ++k) unsee(kfs[k], first_b, points.size());
  for (int k = 3; k < 6; ++k) unsee(kfs[k], first_a, first_b);
  for (KeyFrame* kf : kfs) kf->updateConnections();

  GroundPlaneOptions own, pooled;
  own.pool_keyframes = 0;
  pooled.pool_keyframes = 1;  // keyframes 2 and 3 pool both roads, 0 and 5 one only
  for (KeyFrame* kf : kfs) EXPECT_FALSE(fitGroundPlane(*kf, own, Eigen::Vector3d::UnitY(), 20.0).has_value());
  EXPECT_FALSE(fitGroundPlane(*kfs[0], pooled, Eigen::Vector3d::UnitY(), 20.0).has_value());
  for (int k : {2, 3}) {
    const auto plane = fitGroundPlane(*kfs[k], pooled, Eigen::Vector3d::UnitY(), 20.0);
    ASSERT_TRUE(plane.has_value()) << "keyframe " << k;
    EXPECT_NEAR(plane->height, kHeight, 0.02 * kHeight);
    EXPECT_GE(plane->inliers.size(), static_cast<size_t>(2 * n - 2)) << "both roads' points";
    for (MapPoint* mp : plane->inliers) EXPECT_NEAR(mp->position.y(), kHeight, 0.06) << "a non-road point is an inlier";
  }
}

TEST(GroundReference, IsTheMedianHeightAndMeanNormalOfTheFirstFits) {
  GroundReference ref(5);
  const double heights[] = {1.0, 2.0, 3.0, 100.0};
  for (double h : heights) {
    GroundPlane p;
    p.height = h;
    ref.add(p);
  }
  GroundPlane nan_plane;
  nan_plane.height = std::numeric_limits<double>::quiet_NaN();
  ref.add(nan_plane);
  EXPECT_FALSE(ref.ready()) << "a non-finite height is not a sample";
  GroundPlane last;
  last.height = 4.0;
  last.normal_cam = Eigen::Vector3d(0, std::cos(0.1), std::sin(0.1));
  ref.add(last);
  ASSERT_TRUE(ref.ready());
  EXPECT_DOUBLE_EQ(ref.height(), 3.0);
  EXPECT_NEAR(ref.normal().norm(), 1.0, 1e-12);
  EXPECT_GT(ref.normal().z(), 0.0);
  last.height = 50.0;
  ref.add(last);
  EXPECT_DOUBLE_EQ(ref.height(), 3.0) << "the reference does not move once set";
}

// Metric scale needs fits that agree: a window of the latest fits slides until their spread is small.
TEST(GroundReference, WithASpreadLimitWaitsForAgreeingFitsAndRescales) {
  GroundReference ref(3, 0.1);
  auto add = [&](double h) {
    GroundPlane p;
    p.height = h;
    ref.add(p);
  };
  add(1.0);
  add(2.0);
  add(3.0);
  EXPECT_FALSE(ref.ready()) << "1, 2, 3 spread by half their median: no scale from them";
  add(1.5);
  EXPECT_FALSE(ref.ready()) << "the window 2, 3, 1.5 still spreads by a quarter";
  add(1.52);
  ASSERT_TRUE(ref.ready()) << "3, 1.5, 1.52: two of three agree (median absolute deviation)";
  EXPECT_DOUBLE_EQ(ref.height(), 1.52);
  EXPECT_NEAR(ref.spread(), 0.02 / 1.52, 1e-12);
  ref.rescale(1.1);
  EXPECT_DOUBLE_EQ(ref.height(), 1.52 * 1.1);
}

// Rescaling a map scales every translation and distance and keeps every reprojection.
TEST(MapRescale, ScalesKeyframesPointsAndDistancesAlike) {
  std::mt19937 rng(3);
  const ScalePyramid pyr(8, 1.2);
  Map map;
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  T_cw.translation() = Eigen::Vector3d(0.2, -0.1, 0.5);
  KeyFrame* kf = singleKeyFrame(map, pyr, T_cw, roadPoints(50, rng, 0.0));
  MapPoint* mp = kf->validPoints().front();
  mp->updateNormalAndDepth();
  const Eigen::Vector3d p_cam = kf->T_cw * mp->position;
  const Eigen::Vector2d uv(p_cam.x() / p_cam.z(), p_cam.y() / p_cam.z());
  const float max_d = mp->max_distance;
  map.rescale(20.0);
  EXPECT_TRUE(kf->T_cw.translation().isApprox(20.0 * T_cw.translation()));
  const Eigen::Vector3d q_cam = kf->T_cw * mp->position;
  EXPECT_NEAR(q_cam.z(), 20.0 * p_cam.z(), 1e-9);
  EXPECT_NEAR(q_cam.x() / q_cam.z(), uv.x(), 1e-12);
  EXPECT_NEAR(q_cam.y() / q_cam.z(), uv.y(), 1e-12);
  EXPECT_FLOAT_EQ(mp->max_distance, 20.0f * max_d);
}

// Points made on an object that starts moving leave the map; other points stay.
TEST(MapObjects, DropObjectPointsRemovesOnlyThatObject) {
  std::mt19937 rng(4);
  const ScalePyramid pyr(8, 1.2);
  Map map;
  KeyFrame* kf = singleKeyFrame(map, pyr, Eigen::Isometry3d::Identity(), roadPoints(30, rng, 0.0));
  auto points = kf->validPoints();
  for (size_t i = 0; i < points.size(); ++i) points[i]->object_id = i < 10 ? 7 : (i < 15 ? 8 : -1);
  EXPECT_EQ(map.dropObjectPoints(7), 10);
  int live7 = 0, live8 = 0, background = 0;
  for (MapPoint* mp : map.points()) {
    if (mp->bad) continue;
    live7 += mp->object_id == 7;
    live8 += mp->object_id == 8;
    background += mp->object_id < 0;
  }
  EXPECT_EQ(live7, 0);
  EXPECT_EQ(live8, 5);
  EXPECT_EQ(background, static_cast<int>(points.size()) - 15);
  EXPECT_EQ(map.dropObjectPoints(7), 0);
}

// Five keyframes 1 m apart over a road; the start map is the truth scaled by 1.15 about the origin
// keyframe, so every reprojection is exact and only the prior can tell the scale.
TEST(GroundPrior, LocalBaPullsAScaledMapBackToTheReferenceHeight) {
  std::mt19937 rng(6);
  auto points = roadPoints(120, rng, 0.005);
  const auto other = clutter(rng);
  points.insert(points.end(), other.begin(), other.end());
  std::vector<Eigen::Isometry3d> truth, start;
  const double s = 1.15;
  for (int k = 0; k < 5; ++k) {
    Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
    T_wc.translation() = Eigen::Vector3d(0, 0, 1.0 * k);
    truth.push_back(T_wc.inverse());
    T_wc.translation() *= s;
    start.push_back(T_wc.inverse());
  }
  std::vector<Eigen::Vector3d> start_points;
  for (const auto& p : points) start_points.push_back(s * p);
  auto run = [&](bool with_prior) {
    const ScalePyramid pyr(8, 1.2);
    Map map;
    const auto kfs = test::buildMap(map, kCam, pyr, truth, start, points, start_points, 0.3, 7);
    GroundReference ref(1);
    GroundPlane road;
    road.height = kHeight;
    ref.add(road);
    const optimize::GroundPrior prior{GroundPlaneOptions{}, &ref};
    const auto report = optimize::localBundleAdjustment(kfs.back(), map, optimize::BundleAdjustmentOptions{},
                                                        with_prior ? &prior : nullptr);
    if (with_prior) {
      EXPECT_GE(report.ground_keyframes, 4);
      EXPECT_GE(report.ground_residuals, 400);
    } else {
      EXPECT_EQ(report.ground_residuals, 0);
    }
    return kfs.back()->centre().norm() / 4.0;  // estimated scale of the last keyframe's distance
  };
  EXPECT_NEAR(run(false), s, 0.02) << "without the prior the scale is free and stays";
  EXPECT_NEAR(run(true), 1.0, 0.02) << "the prior restores the reference height";
}

}  // namespace
}  // namespace beslam::orb
