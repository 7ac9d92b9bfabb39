// Problems on simulated geometry: pose-only optimisation with outliers and against Ceres, local BA reducing
// the reprojection error of perturbed keyframes and points, our Schur LM against Ceres (local and global BA).
#include <ceres/autodiff_cost_function.h>
#include <ceres/problem.h>
#include <ceres/rotation.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <opencv2/core/utility.hpp>
#include <random>

#include "features/scale_pyramid.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "map_builder.hpp"
#include "optimize/bundle_adjustment.hpp"
#include "optimize/cost_functions.hpp"
#include "optimize/pose_optimizer.hpp"
#include "optimize/schur_lm.hpp"
#include "optimize/se3.hpp"

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

// The points seen from `truth` with Gaussian pixel noise (sigma px, seeded); every `every`-th moved by
// `outlier` px (a gross outlier).
std::vector<optimize::PoseObservation> observe(const Eigen::Isometry3d& truth,
                                               const std::vector<Eigen::Vector3d>& points, unsigned seed, double sigma,
                                               size_t every, const Eigen::Vector2d& outlier) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, sigma);
  std::vector<optimize::PoseObservation> obs;
  for (size_t i = 0; i < points.size(); ++i) {
    Eigen::Vector2d uv = proj(truth, points[i]) + Eigen::Vector2d(noise(rng), noise(rng));
    if (i % every == 0) uv += outlier;
    obs.push_back({points[i], uv, 1.0});
  }
  return obs;
}

TEST(PoseOptimizer, RecoversThePoseAndFlagsOutliers) {
  const Eigen::Isometry3d truth = poseAt(1.0, 0.03);
  const auto points = randomPoints(300, 5);
  const auto obs = observe(truth, points, 6, 0.7, 10, {40, -25});  // 10 % gross outliers
  Eigen::Isometry3d T = poseAt(0.8, 0.0);                          // the constant-velocity guess is off
  std::vector<bool> outlier;
  const int inliers = optimize::optimizePose(kCam, obs, T, outlier);
  EXPECT_GE(inliers, 250);
  int flagged = 0;
  for (size_t i = 0; i < points.size(); i += 10) flagged += outlier[i];
  EXPECT_GE(flagged, 29);
  EXPECT_LT((T.translation() - truth.translation()).norm(), 0.02);
  EXPECT_LT(Eigen::AngleAxisd(T.linear() * truth.linear().transpose()).angle(), 1e-3);
}

// Reprojection of a fixed point for a pose as angle-axis and translation (a parameterisation of its own,
// so Ceres' solve below does not share our solver's tangent, Jacobians or steps).
struct AngleAxisReprojection {
  AngleAxisReprojection(const Eigen::Vector3d& pw, const Eigen::Vector2d& uv) : pw_(pw), uv_(uv) {}
  template <typename T>
  bool operator()(const T* aa, const T* t, T* r) const {
    const T p[3] = {T(pw_.x()), T(pw_.y()), T(pw_.z())};
    T pc[3];
    ceres::AngleAxisRotatePoint(aa, p, pc);
    for (int i = 0; i < 3; ++i) pc[i] += t[i];
    r[0] = kCam.fx * pc[0] / pc[2] + kCam.cx - uv_.x();
    r[1] = kCam.fy * pc[1] / pc[2] + kCam.cy - uv_.y();
    return true;
  }
  Eigen::Vector3d pw_;
  Eigen::Vector2d uv_;
};

// The last round is plain least squares over the inliers: Ceres, started from the same guess on the same
// inliers and run to its tightest tolerances, must find the same minimum. Ours stops on Ceres' default
// tolerances (a relative cost change of 1e-6), so they agree to a few micrometres, not to the last bit.
TEST(PoseOptimizer, FindsTheMinimumCeresFinds) {
  const Eigen::Isometry3d truth = poseAt(2.0, -0.05);
  const auto points = randomPoints(400, 11);
  const auto obs = observe(truth, points, 12, 1.0, 8, {-30, 35});
  const Eigen::Isometry3d guess = poseAt(1.7, -0.02);
  Eigen::Isometry3d T = guess;
  std::vector<bool> outlier;
  const int inliers = optimize::optimizePose(kCam, obs, T, outlier, {4, 50, 5.991});
  ASSERT_GE(inliers, 300);

  const Eigen::AngleAxisd start(guess.linear());
  double aa[3] = {start.angle() * start.axis().x(), start.angle() * start.axis().y(), start.angle() * start.axis().z()};
  double t[3] = {guess.translation().x(), guess.translation().y(), guess.translation().z()};
  ceres::Problem problem;
  for (size_t i = 0; i < obs.size(); ++i)
    if (!outlier[i])
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<AngleAxisReprojection, 2, 3, 3>(
                                   new AngleAxisReprojection(obs[i].point_world, obs[i].pixel)),
                               nullptr, aa, t);
  ceres::Solver::Options options;
  options.max_num_iterations = 100;
  options.function_tolerance = options.parameter_tolerance = options.gradient_tolerance = 1e-16;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  ASSERT_TRUE(summary.IsSolutionUsable());
  const Eigen::Vector3d aa_ceres(aa[0], aa[1], aa[2]);
  const Eigen::Matrix3d R_ceres = Eigen::AngleAxisd(aa_ceres.norm(), aa_ceres.normalized()).toRotationMatrix();
  EXPECT_LT((T.translation() - Eigen::Vector3d(t[0], t[1], t[2])).norm(), 2e-5);
  EXPECT_LT(Eigen::AngleAxisd(T.linear() * R_ceres.transpose()).angle(), 2e-6);
  // And both are near the truth (the noise is 1 px).
  EXPECT_LT((T.translation() - truth.translation()).norm(), 0.05);
}

// 5 keyframes observing 200 points, all but the first perturbed (the first is poseAt(0, 0)), built into
// `map`; with 10 % of the observations of the last keyframe moved 30 px (outliers) when `outliers`.
std::vector<KeyFrame*> perturbedScene(Map& map, const ScalePyramid& pyr, bool outliers) {
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
  std::vector<KeyFrame*> kfs = test::buildMap(map, kCam, pyr, truth, start, points, start_points, 0.5, 9);
  if (outliers) {  // a test-only edit of the keyframe's (shared, const) features, before anything reads them
    auto& keypoints = const_cast<FeatureSet&>(*kfs.back()->features).keypoints;
    for (size_t i = 0; i < keypoints.size(); i += 10) keypoints[i].pt.x += 30;
  }
  return kfs;
}

TEST(BundleAdjustment, LocalBaReducesReprojectionError) {
  const ScalePyramid pyr(8, 1.2);
  Map map;
  const std::vector<KeyFrame*> kfs = perturbedScene(map, pyr, false);
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
  EXPECT_EQ(kfs[0]->T_cw.matrix(), poseAt(0, 0).matrix()) << "the origin keyframe stays fixed";
}

std::vector<Eigen::Isometry3d> poses(const std::vector<KeyFrame*>& kfs) {
  std::vector<Eigen::Isometry3d> out;
  for (const KeyFrame* kf : kfs) out.push_back(kf->T_cw);
  return out;
}

// Our Schur LM takes Ceres' LM steps: from the same start both reach the same poses and drop the same
// outliers.
TEST(BundleAdjustment, SchurLmAndCeresReachTheSameMinimum) {
  const ScalePyramid pyr(8, 1.2);
  Map map_ceres, map_schur;
  const auto kfs_ceres = perturbedScene(map_ceres, pyr, true);
  const auto kfs_schur = perturbedScene(map_schur, pyr, true);
  optimize::BundleAdjustmentOptions options;
  options.solver = optimize::BaSolver::Ceres;
  const auto ceres_report = optimize::localBundleAdjustment(kfs_ceres.back(), map_ceres, options);
  options.solver = optimize::BaSolver::SchurLm;
  const auto schur_report = optimize::localBundleAdjustment(kfs_schur.back(), map_schur, options);
  EXPECT_EQ(schur_report.outliers_removed, ceres_report.outliers_removed);
  EXPECT_GE(schur_report.outliers_removed, 20);
  EXPECT_NEAR(schur_report.final_cost, ceres_report.final_cost, 1e-9 * ceres_report.final_cost);
  for (size_t k = 0; k < kfs_ceres.size(); ++k) {
    // The same steps (Ceres' damping and stopping rules), so the same poses but for rounding.
    EXPECT_LT((kfs_schur[k]->T_cw.translation() - kfs_ceres[k]->T_cw.translation()).norm(), 1e-9) << k;
    EXPECT_LT(Eigen::AngleAxisd(kfs_schur[k]->T_cw.linear() * kfs_ceres[k]->T_cw.linear().transpose()).angle(), 1e-9)
        << k;
  }
}

// The work is split into fixed ranges summed in order: one thread or two give the same bits.
TEST(BundleAdjustment, SchurLmGivesTheSameBitsOnOneThreadAndTwo) {
  const ScalePyramid pyr(8, 1.2);
  std::vector<std::vector<Eigen::Isometry3d>> results;
  const int threads_before = cv::getNumThreads();
  for (int threads : {1, 2}) {
    cv::setNumThreads(threads);
    Map map;
    const auto kfs = perturbedScene(map, pyr, true);
    optimize::localBundleAdjustment(kfs.back(), map, optimize::BundleAdjustmentOptions{});
    results.push_back(poses(kfs));
  }
  cv::setNumThreads(threads_before);
  for (size_t k = 0; k < results[0].size(); ++k) EXPECT_EQ(results[0][k].matrix(), results[1][k].matrix()) << k;
}

// Block-sparse Schur LM and Ceres' sparse Schur LM on a global BA of a 90-keyframe road (past
// SchurLevenbergMarquardt::kMaxDensePoses, so solved block-sparse): the same steps, so the same minimum
// but for rounding; and the same bits on one thread and two.
TEST(BundleAdjustment, GlobalBaSparseSchurLmAndCeresReachTheSameMinimum) {
  const ScalePyramid pyr(8, 1.2);
  Map map_ceres, map_schur;
  const auto kfs_ceres = test::buildRoad(map_ceres, kCam, pyr, 90, 10, 11);
  const auto kfs_schur = test::buildRoad(map_schur, kCam, pyr, 90, 10, 11);
  ASSERT_GT(static_cast<int>(kfs_schur.size()) - 1, optimize::SchurLevenbergMarquardt::kMaxDensePoses);
  const auto ceres_report =
      optimize::globalBundleAdjustment(map_ceres, 10, optimize::plainOptions(optimize::BaSolver::Ceres));
  const auto schur_report =
      optimize::globalBundleAdjustment(map_schur, 10, optimize::plainOptions(optimize::BaSolver::SchurLm));
  EXPECT_GT(schur_report.initial_cost, 50 * schur_report.final_cost);
  EXPECT_NEAR(schur_report.initial_cost, ceres_report.initial_cost, 1e-9 * ceres_report.initial_cost);
  EXPECT_NEAR(schur_report.final_cost, ceres_report.final_cost, 1e-8 * ceres_report.final_cost);
  for (size_t k = 0; k < kfs_ceres.size(); ++k) {
    EXPECT_LT((kfs_schur[k]->T_cw.translation() - kfs_ceres[k]->T_cw.translation()).norm(), 1e-7) << k;
    EXPECT_LT(Eigen::AngleAxisd(kfs_schur[k]->T_cw.linear() * kfs_ceres[k]->T_cw.linear().transpose()).angle(), 1e-8)
        << k;
  }
  EXPECT_EQ(kfs_schur[0]->T_cw.matrix(), test::roadAt(0).inverse().matrix()) << "the origin keyframe stays fixed";

  std::vector<std::vector<Eigen::Isometry3d>> results;
  const int threads_before = cv::getNumThreads();
  for (int threads : {1, 2}) {
    cv::setNumThreads(threads);
    Map map;
    const auto kfs = test::buildRoad(map, kCam, pyr, 90, 10, 11);
    optimize::globalBundleAdjustment(map, 10, optimize::plainOptions(optimize::BaSolver::SchurLm));
    results.push_back(poses(kfs));
  }
  cv::setNumThreads(threads_before);
  for (size_t k = 0; k < results[0].size(); ++k) EXPECT_EQ(results[0][k].matrix(), results[1][k].matrix()) << k;
}

// A global BA (after a loop correction) on a map held metric keeps the metric terms local BA has: a road map
// grown 1 % about its first keyframe (a loop correction's scale change; ranges farther off than 3 sigma are gated
// out) comes back to its metric length with the keypoints' LiDAR ranges, or with the parked cars' keypoint
// ranges (object_scale_hold: ranges), and stays 1 % long without (the scale is free in a monocular BA).
TEST(BundleAdjustment, GlobalBaWithRangePriorsHoldsTheMetricScale) {
  const ScalePyramid pyr(8, 1.2);
  auto length = [](const std::vector<KeyFrame*>& kfs) {
    return (kfs.back()->T_cw.inverse().translation() - kfs.front()->T_cw.inverse().translation()).norm();
  };
  using test::RoadRanges;
  std::map<RoadRanges, double> ratio;
  for (const RoadRanges ranges : {RoadRanges::None, RoadRanges::Lidar, RoadRanges::Object}) {
    Map map;
    const auto kfs = test::buildRoad(map, kCam, pyr, 30, 10, 12, 1.0, ranges);
    const double truth = (test::roadAt(29).translation() - test::roadAt(0).translation()).norm();
    const Eigen::Vector3d origin = kfs[0]->T_cw.inverse().translation();
    for (KeyFrame* kf : kfs) {  // grow the map by 1 % about the first camera
      Eigen::Isometry3d T_wc = kf->T_cw.inverse();
      T_wc.translation() = origin + 1.01 * (T_wc.translation() - origin);
      kf->T_cw = T_wc.inverse();
    }
    for (MapPoint* mp : map.points()) mp->position = origin + 1.01 * (mp->position - origin);
    // The options LocalMapper::metricTerms gives a metric map of either kind: both sigmas set.
    optimize::BundleAdjustmentOptions options = optimize::plainOptions(optimize::BaSolver::SchurLm);
    options.lidar_range_sigma = 0.05;
    options.object_range_sigma = 0.05;
    options.object_range_priors = true;
    const auto report = optimize::globalBundleAdjustment(map, 20, options);
    EXPECT_EQ(report.lidar_range_residuals > 0, ranges == RoadRanges::Lidar);
    EXPECT_EQ(report.object_range_residuals > 0, ranges == RoadRanges::Object);
    ratio[ranges] = length(kfs) / truth;
  }
  std::printf("length over truth: %.5f without ranges, %.5f with LiDAR ranges, %.5f with parked cars' ranges\n",
              ratio[RoadRanges::None], ratio[RoadRanges::Lidar], ratio[RoadRanges::Object]);
  EXPECT_NEAR(ratio[RoadRanges::None], 1.01, 0.002) << "without ranges the scale stays where it was";
  EXPECT_NEAR(ratio[RoadRanges::Lidar], 1.0, 0.002) << "the scan's ranges bring it back";
  EXPECT_NEAR(ratio[RoadRanges::Object], 1.0, 0.002) << "the parked cars' ranges bring it back";
}

// Concurrent mapping's hooks: the callback runs after each pass, and a stop request skips the refining
// pass (ORB-SLAM2's interrupted BA) but still removes the outliers and writes the result back.
TEST(BundleAdjustment, StopEarlySkipsTheRefiningPassAndKeepsTheResult) {
  const ScalePyramid pyr(8, 1.2);
  Map map_full, map_cut;
  const auto kfs_full = perturbedScene(map_full, pyr, true);
  const auto kfs_cut = perturbedScene(map_cut, pyr, true);
  int passes = 0;
  optimize::BundleAdjustmentOptions options;
  options.between_passes = [&passes] { ++passes; };
  const auto full = optimize::localBundleAdjustment(kfs_full.back(), map_full, options);
  EXPECT_EQ(passes, 2);
  EXPECT_FALSE(full.stopped_early);
  const std::atomic<bool> stop{true};
  options.stop_early = &stop;
  passes = 0;
  const auto cut = optimize::localBundleAdjustment(kfs_cut.back(), map_cut, options);
  EXPECT_EQ(passes, 1);
  EXPECT_TRUE(cut.stopped_early);
  EXPECT_GE(cut.outliers_removed, 20);
  EXPECT_LT(cut.final_cost, cut.initial_cost);
  double moved = 0;  // the robust pass's result is written back: the poses left their start
  for (size_t k = 1; k < kfs_cut.size(); ++k)
    moved += (kfs_cut[k]->T_cw.translation() - kfs_full[k]->T_cw.translation()).norm();
  EXPECT_GT(moved, 0.0) << "a cut BA is not the full one";
  Map map_start;
  const auto kfs_start = perturbedScene(map_start, pyr, true);
  for (size_t k = 1; k < kfs_cut.size(); ++k) EXPECT_NE(kfs_cut[k]->T_cw.matrix(), kfs_start[k]->T_cw.matrix()) << k;
}

// Residuals of 3 rows on a fixed pose: a box centre seen from two fixed cameras puts the anchor where the
// two measurements agree (the mean of their world positions); a vector without a residual stays.
TEST(SchurLevenbergMarquardt, ThreeRowResidualsOnFixedPoses) {
  double pose_a[7], pose_b[7];
  Eigen::Isometry3d T_a = Eigen::Isometry3d::Identity(), T_b = Eigen::Isometry3d::Identity();
  T_b.translation() = Eigen::Vector3d(1, 0, -2);
  optimize::poseToParams(T_a, pose_a);
  optimize::poseToParams(T_b, pose_b);
  const Eigen::Vector3d p_world(2, 1, 10), noise(0.1, -0.1, 0.2);
  const optimize::BoxCentreCost seen_a(T_a * p_world + noise, 0.1), seen_b(T_b * p_world - noise, 0.1);
  double anchor[3] = {0, 0, 5}, idle[3] = {7, 8, 9};
  optimize::SchurLevenbergMarquardt lm;
  const int a = lm.addPose(pose_a, true), b = lm.addPose(pose_b, true);
  const int v = lm.addVector(anchor);
  lm.addVector(idle);
  lm.addResidual(&seen_a, nullptr, a, v);
  lm.addResidual(&seen_b, nullptr, b, v);
  const auto summary = lm.solve(10);
  EXPECT_NEAR(summary.final_cost, 6.0, 1e-9);  // 0.5 * 2 * |noise / sigma|^2: the noise is all that is left
  EXPECT_GT(summary.initial_cost, 1000.0);
  EXPECT_LT((Eigen::Vector3d(anchor[0], anchor[1], anchor[2]) - p_world).norm(), 1e-6);
  EXPECT_EQ(idle[2], 9.0);
  EXPECT_EQ(pose_b[6], -2.0) << "fixed poses do not move";
  const optimize::GroundHeightCost wrong_shape(Eigen::Vector3d::UnitY(), 1.5, 0.1);
  EXPECT_NO_THROW(lm.addResidual(&wrong_shape, nullptr, a, v));  // 1 row on (pose, vector): accepted
}

}  // namespace
}  // namespace beslam::orb
