// Ceres problems on simulated geometry: pose-only optimisation with outliers, local BA reducing the
// reprojection error of perturbed keyframes and points.
#include <gtest/gtest.h>

#include <random>

#include "features/scale_pyramid.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "map_builder.hpp"
#include "optimize/bundle_adjustment.hpp"
#include "optimize/pose_optimizer.hpp"

namespace beslam::orb {
namespace {

const Camera kCam{1226, 370, 718.856, 718.856, 607.19, 185.22};

Eigen::Vector2d proj(const Eigen::Isometry3d& T_cw, const Eigen::Vector3d& pw) { return test::project(kCam, T_cw, pw); }

Eigen::Isometry3d poseAt(double forward, double yaw) {
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  T_wc.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_wc.translation() = Eigen::Vector3d(0.05 * forward, 0, forward);
  return T_wc.inverse();
}

std::vector<Eigen::Vector3d> randomPoints(int n, uint64_t seed) {
  std::mt19937 rng(static_cast<unsigned>(seed));
  std::uniform_real_distribution<double> ux(-6, 6), uy(-2, 2), uz(8, 30);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < n; ++i) p.emplace_back(ux(rng), uy(rng), uz(rng));
  return p;
}

TEST(PoseOptimizer, RecoversThePoseAndFlagsOutliers) {
  const Eigen::Isometry3d truth = poseAt(1.0, 0.03);
  const auto points = randomPoints(300, 5);
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0, 0.7);
  std::vector<optimize::PoseObservation> obs;
  for (size_t i = 0; i < points.size(); ++i) {
    Eigen::Vector2d uv = proj(truth, points[i]) + Eigen::Vector2d(noise(rng), noise(rng));
    if (i % 10 == 0) uv += Eigen::Vector2d(40, -25);  // 10% gross outliers
    obs.push_back({points[i], uv, 1.0});
  }
  Eigen::Isometry3d T = poseAt(0.8, 0.0);  // the constant-velocity guess is off
  std::vector<bool> outlier;
  const int inliers = optimize::optimizePose(kCam, obs, T, outlier);
  EXPECT_GE(inliers, 250);
  int flagged = 0;
  for (size_t i = 0; i < points.size(); i += 10) flagged += outlier[i];
  EXPECT_GE(flagged, 29);
  EXPECT_LT((T.translation() - truth.translation()).norm(), 0.02);
  EXPECT_LT(Eigen::AngleAxisd(T.linear() * truth.linear().transpose()).angle(), 1e-3);
}

// Builds a map of 5 keyframes observing 200 points, perturbs all but the first, runs local BA.
TEST(BundleAdjustment, LocalBaReducesReprojectionError) {
  const ScalePyramid pyr(8, 1.2);
  Map map;
  const auto points = randomPoints(200, 7);
  std::vector<Eigen::Isometry3d> truth;
  for (int k = 0; k < 5; ++k) truth.push_back(poseAt(0.5 * k, 0.01 * k));
  std::mt19937 rng(8);
  std::normal_distribution<double> perturb(0, 0.05);
  std::vector<Eigen::Isometry3d> start(truth);
  for (int k = 1; k < 5; ++k) {
    start[k].translation() += Eigen::Vector3d(perturb(rng), perturb(rng), perturb(rng));
    start[k].linear() = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitX()).toRotationMatrix() * start[k].linear();
  }
  std::vector<Eigen::Vector3d> start_points;
  for (const auto& p : points) start_points.push_back(p + Eigen::Vector3d(perturb(rng), perturb(rng), perturb(rng)));
  const std::vector<KeyFrame*> kfs = test::buildMap(map, kCam, pyr, truth, start, points, start_points, 0.5, 9);
  auto rms = [&] {
    double sum = 0;
    int n = 0;
    for (KeyFrame* kf : kfs)
      for (size_t i = 0; i < kf->points.size(); ++i)
        if (kf->points[i]) {
          const Eigen::Vector2d uv = proj(kf->T_cw, kf->points[i]->position);
          sum += (uv - Eigen::Vector2d(kf->keypoint(i).pt.x, kf->keypoint(i).pt.y)).squaredNorm();
          ++n;
        }
    return std::sqrt(sum / n);
  };
  const double before = rms();
  const auto report = optimize::localBundleAdjustment(kfs.back(), map, optimize::BundleAdjustmentOptions{});
  const double after = rms();
  EXPECT_EQ(report.keyframes, 5);
  EXPECT_GT(before, 5.0);
  EXPECT_LT(after, 1.0);
  EXPECT_LT(report.final_cost, report.initial_cost);
  EXPECT_EQ(kfs[0]->T_cw.matrix(), truth[0].matrix()) << "the origin keyframe stays fixed";
}

}  // namespace
}  // namespace beslam::orb
