// Metric scale from static objects and LiDAR: the ray-box entry that gives a keypoint its metric range,
// the LiDAR range under a keypoint (one surface, never across an edge), the range prior's and the box-centre
// anchor's Jacobians against numeric ones, and that a rescaled map keeps every reprojection.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "features/feature_set.hpp"
#include "optimize/cost_functions.hpp"
#include "optimize/se3.hpp"
#include "scale/lidar_range.hpp"
#include "scale/object_range.hpp"
#include "scale/parked_car_scale.hpp"

namespace beslam::orb {
namespace {

ObjectBox carAhead(double z, double yaw) {
  ObjectBox b;
  b.object_id = 3;
  b.T_cam_box.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  b.T_cam_box.translation() = Eigen::Vector3d(0, 0.9, z);
  b.size = Eigen::Vector3d(4.0, 1.5, 1.8);  // length (box x), height (box y), width (box z)
  return b;
}

TEST(RayBoxEntry, StraightAheadHitsTheNearFace) {
  // Yaw 0: the car's length runs along camera x, its width along z: the near face is z - 0.9.
  const Eigen::Vector3d ray = Eigen::Vector3d(0, 0.9, 10).normalized();  // at the box centre
  const auto t = rayBoxEntry(ray, carAhead(10, 0));
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, (10 - 0.9) / ray.z(), 1e-9);
  // Turned by 90 degrees the length runs along z: the near face is 2 m closer than the centre.
  const auto t90 = rayBoxEntry(ray, carAhead(10, M_PI / 2));
  ASSERT_TRUE(t90);
  EXPECT_NEAR(*t90, 8.0 / ray.z(), 1e-9);
}

TEST(RayBoxEntry, MissesAndInsideGiveNothing) {
  EXPECT_FALSE(rayBoxEntry(Eigen::Vector3d(1, 0, 0.2).normalized(), carAhead(10, 0)));  // far to the right
  EXPECT_FALSE(rayBoxEntry(Eigen::Vector3d(0, 0, -1), carAhead(10, 0)));                // behind the camera
  ObjectBox around = carAhead(0, 0);
  around.T_cam_box.translation() = Eigen::Vector3d::Zero();
  EXPECT_FALSE(rayBoxEntry(Eigen::Vector3d(0, 0, 1), around)) << "a camera inside the box has no range";
}

// A cost over (pose [qx qy qz qw tx ty tz], point [3]) with `rows` residuals: its analytic Jacobians against
// central differences, the pose on the SE(3) left tangent [rho, phi] (the manifold's 7th column is zero).
void expectJacobiansMatchNumericOnes(const ceres::CostFunction& cost, int rows, const Eigen::Isometry3d& T_cw,
                                     const double* point) {
  double pose[7];
  optimize::poseToParams(T_cw, pose);
  std::vector<double> r0(rows), J_pose(rows * 7), J_point(rows * 3);
  const double* params[] = {pose, point};
  double* jac[] = {J_pose.data(), J_point.data()};
  ASSERT_TRUE(cost.Evaluate(params, r0.data(), jac));
  const double eps = 1e-6;
  auto residualsAt = [&](const Eigen::Isometry3d& T, const double* X) {
    double p[7];
    optimize::poseToParams(T, p);
    std::vector<double> r(rows);
    const double* ps[] = {p, X};
    cost.Evaluate(ps, r.data(), nullptr);
    return r;
  };
  for (int k = 0; k < 6; ++k) {  // left update [rho, phi]
    Eigen::Matrix<double, 6, 1> delta = Eigen::Matrix<double, 6, 1>::Zero();
    delta[k] = eps;
    Eigen::Isometry3d plus = Eigen::Isometry3d::Identity(), minus = Eigen::Isometry3d::Identity();
    plus.linear() = optimize::expSO3(delta.tail<3>()).toRotationMatrix();
    plus.translation() = delta.head<3>();
    minus.linear() = optimize::expSO3(-delta.tail<3>()).toRotationMatrix();
    minus.translation() = -delta.head<3>();
    const auto rp = residualsAt(plus * T_cw, point), rm = residualsAt(minus * T_cw, point);
    for (int i = 0; i < rows; ++i)
      EXPECT_NEAR(J_pose[i * 7 + k], (rp[i] - rm[i]) / (2 * eps), 1e-5) << "residual " << i << ", pose tangent " << k;
  }
  for (int i = 0; i < rows; ++i) EXPECT_EQ(J_pose[i * 7 + 6], 0.0);
  for (int k = 0; k < 3; ++k) {
    double xp[3] = {point[0], point[1], point[2]}, xm[3] = {point[0], point[1], point[2]};
    xp[k] += eps, xm[k] -= eps;
    const auto rp = residualsAt(T_cw, xp), rm = residualsAt(T_cw, xm);
    for (int i = 0; i < rows; ++i)
      EXPECT_NEAR(J_point[i * 3 + k], (rp[i] - rm[i]) / (2 * eps), 1e-5) << "residual " << i << ", point " << k;
  }
}

// Keypoints at the given pixels, level 0.
FeatureSet keypointsAt(const std::vector<cv::Point2f>& pixels) {
  FeatureSet f;
  for (const cv::Point2f& p : pixels) f.keypoints.emplace_back(p, 8.0f);
  f.labels.assign(pixels.size(), 0);
  return f;
}

// A 64-beam-like scan of a scene in the camera frame: returns every 0.2 degrees across and 0.4 degrees
// up (from -10 to 10 degrees), of a wall at depth `wall_z` and, where x < 0 (the left half of the image),
// of a box face at depth `near_z` in front of it.
Eigen::Matrix3Xf scanOfWallAndBox(double wall_z, double near_z) {
  std::vector<Eigen::Vector3f> points;
  for (double az = -40; az <= 40; az += 0.2)
    for (double el = -10; el <= 10; el += 0.4) {
      const Eigen::Vector3d ray(std::tan(az * M_PI / 180), std::tan(el * M_PI / 180), 1.0);
      const double z = ray.x() < 0 ? near_z : wall_z;
      points.push_back((ray * z).cast<float>());
    }
  Eigen::Matrix3Xf p(3, static_cast<Eigen::Index>(points.size()));
  for (size_t j = 0; j < points.size(); ++j) p.col(static_cast<Eigen::Index>(j)) = points[j];
  return p;
}

TEST(LidarRange, AKeypointOnOneSurfaceTakesItsRangeAlongItsOwnRay) {
  const Camera camera{1241, 376, 718.856, 718.856, 607.19, 185.22};
  FeatureSet f = keypointsAt({{900, 150}, {900, 300}, {300, 200}, {20, 5}});
  setLidarRanges(f, scanOfWallAndBox(12.0, 6.0), camera);
  ASSERT_EQ(f.lidar_range.size(), 4u);
  for (size_t i : {0u, 1u}) {  // on the wall (x > 0): depth 12 m, range along the keypoint's ray
    const cv::Point2f& pt = f.keypoints[i].pt;
    const double x = (pt.x - camera.cx) / camera.fx, y = (pt.y - camera.cy) / camera.fy;
    EXPECT_NEAR(f.lidar_range[i], 12.0 * std::sqrt(1 + x * x + y * y), 1e-3) << i;
  }
  const cv::Point2f& pt = f.keypoints[2].pt;  // on the box (x < 0): 6 m
  const double x = (pt.x - camera.cx) / camera.fx, y = (pt.y - camera.cy) / camera.fy;
  EXPECT_NEAR(f.lidar_range[2], 6.0 * std::sqrt(1 + x * x + y * y), 1e-3);
  EXPECT_EQ(f.lidar_range[3], 0.0f);  // above the scan's highest beam: no return near it
}

TEST(LidarRange, NoRangeAcrossAnEdgeNorFromReturnsBehindOrAtTheCamera) {
  const Camera camera{1241, 376, 718.856, 718.856, 607.19, 185.22};
  // On the box's edge (x = 0, u = cx): the window sees the box at 6 m and the wall at 12 m.
  FeatureSet f = keypointsAt({{607.19f, 185.22f}, {500, 185}});
  setLidarRanges(f, scanOfWallAndBox(12.0, 6.0), camera);
  EXPECT_EQ(f.lidar_range[0], 0.0f);
  EXPECT_GT(f.lidar_range[1], 0.0f);
  // Returns behind the camera or within min_depth of it (the ego car's own body) are no surface.
  setLidarRanges(f, -scanOfWallAndBox(12.0, 6.0), camera);
  EXPECT_EQ(f.lidar_range[1], 0.0f);
  setLidarRanges(f, scanOfWallAndBox(0.5, 0.5), camera);
  EXPECT_EQ(f.lidar_range[1], 0.0f);
  // Non-finite returns are no surface either; the others still give their range.
  Eigen::Matrix3Xf scan = scanOfWallAndBox(12.0, 6.0);
  for (Eigen::Index j = 0; j < scan.cols(); j += 2) scan.col(j).setConstant(std::numeric_limits<float>::quiet_NaN());
  setLidarRanges(f, scan, camera);
  EXPECT_GT(f.lidar_range[1], 0.0f);
  EXPECT_TRUE(std::isfinite(f.lidar_range[1]));
  // No scan: a range of 0 for every keypoint.
  setLidarRanges(f, Eigen::Matrix3Xf(3, 0), camera);
  EXPECT_EQ(f.lidar_range, std::vector<float>(2, 0.0f));
}

Eigen::Isometry3d someCameraPose() {
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  T_cw.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  T_cw.translation() = Eigen::Vector3d(0.4, -0.2, 1.5);
  return T_cw;
}

TEST(ObjectRangeCost, JacobiansMatchNumericOnes) {
  const Eigen::Isometry3d T_cw = someCameraPose();
  const double point[3] = {1.0, 0.5, 9.0};
  const optimize::ObjectRangeCost cost(9.5, 0.3);
  expectJacobiansMatchNumericOnes(cost, 1, T_cw, point);
  // The residual is (|p_cam| - range) / sigma.
  double pose[7], r;
  optimize::poseToParams(T_cw, pose);
  const double* params[] = {pose, point};
  ASSERT_TRUE(cost.Evaluate(params, &r, nullptr));
  const Eigen::Vector3d p_cam = T_cw * Eigen::Vector3d(point[0], point[1], point[2]);
  EXPECT_NEAR(r, (p_cam.norm() - 9.5) / 0.3, 1e-12);
}

TEST(BoxCentreCost, JacobiansMatchNumericOnesAndTheResidualIsTheCentreOffset) {
  const Eigen::Isometry3d T_cw = someCameraPose();
  const double anchor[3] = {1.0, 0.5, 9.0};
  const Eigen::Vector3d b_cam(2.0, 1.1, 10.5);
  const optimize::BoxCentreCost cost(b_cam, 0.25);
  expectJacobiansMatchNumericOnes(cost, 3, T_cw, anchor);
  double pose[7], r[3];
  optimize::poseToParams(T_cw, pose);
  const double* params[] = {pose, anchor};
  ASSERT_TRUE(cost.Evaluate(params, r, nullptr));
  const Eigen::Vector3d expected = (T_cw * Eigen::Vector3d(anchor[0], anchor[1], anchor[2]) - b_cam) / 0.25;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(r[i], expected[i], 1e-12);
}

// A street: the camera drives 1 m a frame along z in a map whose unit is 20 m (true scale 20); parked
// cars along both sides, one car driving ahead at half the ego speed, boxes with 10 cm noise.
struct Street {
  std::vector<std::pair<Eigen::Isometry3d, std::vector<std::pair<int32_t, Eigen::Vector3d>>>> frames;
};

Street street(int n_frames, double ego_step, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.1);
  const std::vector<Eigen::Vector3d> parked = {{-4, 0.8, 12}, {4, 0.8, 18}, {-4, 0.8, 25}, {4, 0.8, 30}, {-4, 0.8, 36}};
  Street s;
  for (int k = 0; k < n_frames; ++k) {
    const Eigen::Vector3d centre_m(0, 0, ego_step * k);
    Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
    T_wc.linear() = Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T_wc.translation() = centre_m / 20.0;  // map units
    std::vector<std::pair<int32_t, Eigen::Vector3d>> boxes;
    auto see = [&](int32_t id, const Eigen::Vector3d& p_world_m) {
      Eigen::Isometry3d T_wc_m = T_wc;
      T_wc_m.translation() = centre_m;
      const Eigen::Vector3d b = T_wc_m.inverse() * p_world_m + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      if (b.z() > 2 && b.z() < 40) boxes.emplace_back(id, b);
    };
    for (size_t j = 0; j < parked.size(); ++j) see(static_cast<int32_t>(j), parked[j]);
    see(100, Eigen::Vector3d(0, 0.8, 10 + 0.5 * ego_step * k));  // the car ahead, at half the ego speed
    s.frames.emplace_back(T_wc, boxes);
  }
  return s;
}

TEST(ParkedCarScale, ParkedCarsAgreeOnTheMapScaleAndTheMovingCarIsOutvoted) {
  ParkedCarScale estimator;
  const Street s = street(20, 1.0, 5);
  for (const auto& [T, boxes] : s.frames) estimator.addFrame(T, boxes);
  const auto e = estimator.estimate();
  ASSERT_TRUE(e);
  EXPECT_NEAR(e->scale, 20.0, 0.2);
  EXPECT_GE(e->tracks, 3);
  estimator.rescale(20.0);  // the map became metric: the same cars now say 1
  const auto e1 = estimator.estimate();
  ASSERT_TRUE(e1);
  EXPECT_NEAR(e1->scale, 1.0, 0.01);
}

TEST(ParkedCarScale, NoEstimateWithoutMotionOrWithoutEnoughCars) {
  ParkedCarScale standing;
  for (const auto& [T, boxes] : street(20, 0.0, 6).frames) standing.addFrame(T, boxes);
  EXPECT_FALSE(standing.estimate()) << "a camera that does not move cannot tell the scale";
  ParkedCarScale brief;
  const Street s = street(5, 1.0, 7);
  for (const auto& [T, boxes] : s.frames) brief.addFrame(T, boxes);
  EXPECT_FALSE(brief.estimate()) << "5 frames are fewer than a track needs";
}

}  // namespace
}  // namespace beslam::orb
