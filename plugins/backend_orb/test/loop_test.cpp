// Loop-closure geometry: Sim3 alignment of matched points (exact, SE3 when the scale is fixed,
// degenerate sets refused), seeded RANSAC over 3D-3D matches with outliers, and the Sim3 pose graph
// removing a known scale-and-position drift around a loop.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "loop/pose_graph.hpp"
#include "loop/sim3.hpp"

namespace lp = beslam::orb::loop;

namespace {

lp::Sim3 makeSim3(double s, const Eigen::Vector3d& axis_angle, const Eigen::Vector3d& t) {
  lp::Sim3 S;
  S.s = s;
  S.R = axis_angle.norm() > 0 ? Eigen::AngleAxisd(axis_angle.norm(), axis_angle.normalized()).toRotationMatrix()
                              : Eigen::Matrix3d::Identity();
  S.t = t;
  return S;
}

double rotationErrorDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / M_PI;
}

}  // namespace

TEST(Sim3, AlignPointsRecoversTheTransform) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5, 5);
  const lp::Sim3 truth = makeSim3(2.5, {0.1, -0.3, 0.2}, {1, 2, -3});
  std::vector<Eigen::Vector3d> a, b;
  for (int i = 0; i < 20; ++i) {
    a.emplace_back(u(rng), u(rng), u(rng) + 10);
    b.push_back(truth * a.back());
  }
  const auto S = lp::alignPoints(a, b, false);
  ASSERT_TRUE(S.has_value());
  EXPECT_NEAR(S->s, 2.5, 1e-9);
  EXPECT_LT(rotationErrorDeg(S->R, truth.R), 1e-6);
  EXPECT_LT((S->t - truth.t).norm(), 1e-8);
  // Composition and inverse agree with the action on points.
  const Eigen::Vector3d p(0.3, -1, 4);
  EXPECT_LT(((S->inverse() * *S) * p - p).norm(), 1e-9);

  // Fixed scale: a rigid motion is recovered with s = 1.
  const lp::Sim3 rigid = makeSim3(1.0, {0, 0.5, 0}, {0, 0, 1});
  for (size_t i = 0; i < a.size(); ++i) b[i] = rigid * a[i];
  const auto T = lp::alignPoints(a, b, true);
  ASSERT_TRUE(T.has_value());
  EXPECT_EQ(T->s, 1.0);
  EXPECT_LT(rotationErrorDeg(T->R, rigid.R), 1e-6);
}

TEST(Sim3, DegeneratePointSetsAreRefused) {
  EXPECT_FALSE(lp::alignPoints({{0, 0, 1}, {1, 0, 1}}, {{0, 0, 1}, {1, 0, 1}}, false).has_value());
  EXPECT_FALSE(lp::alignPoints({{0, 0, 1}, {1, 0, 1}, {2, 0, 1}}, {{0, 0, 1}, {1, 0, 1}, {2, 0, 1}}, false));
  EXPECT_FALSE(lp::alignPoints({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}, {{0, 0, 1}, {1, 0, 1}, {2, 0, 1}}, false));
}

TEST(Sim3, RansacFindsTheLoopTransformAmongOutliers) {
  const lp::PinholeIntrinsics camera{700, 700, 600, 180};
  const lp::Sim3 S_21 = makeSim3(0.7, {0.02, 0.15, -0.01}, {0.4, 0.05, -0.6});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> pixel(0, 0.7);
  std::vector<lp::PointMatch> matches;
  for (int i = 0; i < 120; ++i) {
    lp::PointMatch m;
    m.p_c1 = Eigen::Vector3d(8 * u(rng), 2 * u(rng), 12 + 8 * u(rng));
    m.p_c2 = S_21 * m.p_c1;
    if (i % 5 < 2) m.p_c2 = Eigen::Vector3d(8 * u(rng), 2 * u(rng), 10 + 5 * u(rng));  // 40 % wrong matches
    m.uv1 = camera.project(m.p_c1) + Eigen::Vector2d(pixel(rng), pixel(rng));
    m.uv2 = camera.project(S_21 * m.p_c1) + Eigen::Vector2d(pixel(rng), pixel(rng));
    matches.push_back(m);
  }
  lp::Sim3RansacOptions options;
  options.seed = 11;
  const auto result = lp::ransacSim3(matches, camera, options);
  ASSERT_TRUE(result.has_value());
  EXPECT_GE(result->inlier_count, 70);
  EXPECT_LE(result->inlier_count, 75);  // the 72 right matches, maybe a lucky wrong one
  EXPECT_NEAR(result->S_21.s, 0.7, 0.01);
  EXPECT_LT(rotationErrorDeg(result->S_21.R, S_21.R), 0.2);
  for (int i = 0; i < 120; i += 5) EXPECT_TRUE(result->inliers[static_cast<size_t>(i) + 2]) << i;
  // Seeded: the same seed gives the same model.
  const auto again = lp::ransacSim3(matches, camera, options);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->inlier_count, result->inlier_count);
  EXPECT_EQ(again->S_21.s, result->S_21.s);
  // Too few matches: nothing.
  matches.resize(10);
  EXPECT_FALSE(lp::ransacSim3(matches, camera, options).has_value());
}

// A camera driving a circle of 40 poses; odometry accumulates a scale drift (1 % per step) and a small
// heading error; a loop edge ties the last pose to the first with the true relative transform. The
// pose graph (first node fixed) removes most of the drift.
TEST(PoseGraph, LoopEdgeRemovesScaleAndPositionDrift) {
  const int n = 40;
  std::vector<lp::Sim3> truth;  // S_cw, s = 1
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n;
    Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
    T_wc.linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T_wc.translation() = Eigen::Vector3d(20 * std::cos(a), 0, 20 * std::sin(a));
    truth.push_back(lp::Sim3::fromIsometry(T_wc.inverse()));
  }
  lp::PoseGraph graph;
  graph.S_cw.push_back(truth[0]);
  const lp::Sim3 drift = makeSim3(1.01, {0, 0.004, 0}, {0.02, 0, 0});
  for (int k = 1; k < n; ++k) {
    // Odometry measurement S_k * S_{k-1}^-1 with drift, chained into the start values.
    const lp::Sim3 measured = drift * (truth[k] * truth[k - 1].inverse());
    graph.S_cw.push_back(measured * graph.S_cw.back());
    graph.edges.push_back({k, k - 1, measured, 1.0});
  }
  graph.edges.push_back({n - 1, 0, truth[n - 1] * truth[0].inverse(), 1.0});  // the loop
  graph.fixed.assign(n, false);
  graph.fixed[0] = true;

  auto centreError = [&](const std::vector<lp::Sim3>& S) {
    double worst = 0;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d c = S[k].inverse().t, c_true = truth[k].inverse().t;
      worst = std::max(worst, (c - c_true).norm());
    }
    return worst;
  };
  const double before = centreError(graph.S_cw);
  const lp::PoseGraphResult result = lp::optimizePoseGraph(graph, 20, false);
  const double after = centreError(result.S_cw);
  EXPECT_GT(before, 5.0);
  EXPECT_LT(after, 0.25 * before);
  EXPECT_LT(result.final_cost, 0.01 * result.initial_cost);
  EXPECT_EQ(result.S_cw[0].t, graph.S_cw[0].t);  // fixed node untouched

  // With the scale fixed no node changes its scale.
  const lp::PoseGraphResult rigid = lp::optimizePoseGraph(graph, 20, true);
  for (int k = 0; k < n; ++k) EXPECT_NEAR(rigid.S_cw[k].s, graph.S_cw[k].s, 1e-12);
}
