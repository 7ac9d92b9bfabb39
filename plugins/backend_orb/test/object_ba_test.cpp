// Object landmarks in local BA (objects/, docs/object-ba.md): the factors' Jacobians against numeric
// ones, the nearest-surface association against brute force, an object BA that pulls back a keyframe
// whose baseline (monocular scale) is wrong, a car's points weighing as one surface observation, the same
// terms in the global BA after a loop, dropObject, landmarks following a loop correction, the map-file
// round trip, and `off` leaving trajectories byte-identical.
#include "objects/object_ba.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <random>
#include <set>

#include "beslam/formats/align.hpp"
#include "beslam_orb/orb_slam.hpp"
#include "features/scale_pyramid.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "map_builder.hpp"
#include "objects/object_factors.hpp"
#include "objects/surface_index.hpp"
#include "optimize/bundle_adjustment.hpp"
#include "optimize/se3.hpp"
#include "synthetic_world.hpp"

namespace beslam::orb {
namespace {

const Camera kCam{1226, 370, 718.856, 718.856, 607.19, 185.22};

Eigen::Isometry3d randomPose(std::mt19937& rng, double t_range) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng) + 2).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * t_range;
  return T;
}

// Samples on the faces of a car-sized box (object frame: x forward, y left, z up), `step` apart.
std::vector<Eigen::Vector3d> boxSurface(const Eigen::Vector3d& size, double step) {
  std::vector<Eigen::Vector3d> out;
  const Eigen::Vector3d h = size / 2;
  const int n[3] = {static_cast<int>(size.x() / step), static_cast<int>(size.y() / step),
                    static_cast<int>(size.z() / step)};
  for (int i = 0; i <= n[0]; ++i)
    for (int j = 0; j <= n[1]; ++j)
      for (int k = 0; k <= n[2]; ++k) {
        if (i != 0 && i != n[0] && j != 0 && j != n[1] && k != 0 && k != n[2]) continue;  // inside
        out.emplace_back(-h.x() + size.x() * i / n[0], -h.y() + size.y() * j / n[1], -h.z() + size.z() * k / n[2]);
      }
  return out;
}

// Central differences of residual(params) along each tangent direction of block `b`.
template <int R>
Eigen::MatrixXd numericJacobian(const ceres::CostFunction& cost, std::vector<std::vector<double>> params, int b,
                                bool se3) {
  const int tangent = se3 ? 6 : static_cast<int>(params[b].size());
  Eigen::MatrixXd J(R, tangent);
  optimize::SE3LeftManifold manifold;
  const double eps = 1e-6;
  for (int k = 0; k < tangent; ++k) {
    Eigen::Matrix<double, R, 1> r[2];
    for (int side = 0; side < 2; ++side) {
      auto p = params;
      if (se3) {
        double delta[6] = {0, 0, 0, 0, 0, 0};
        delta[k] = side ? eps : -eps;
        manifold.Plus(params[b].data(), delta, p[b].data());
      } else {
        p[b][k] += side ? eps : -eps;
      }
      std::vector<const double*> ptrs;
      for (auto& v : p) ptrs.push_back(v.data());
      cost.Evaluate(ptrs.data(), r[side].data(), nullptr);
    }
    J.col(k) = (r[1] - r[0]) / (2 * eps);
  }
  return J;
}

// Evaluates a two-block cost (R residuals; P0 and P1 parameters) and checks its analytic Jacobians against
// central differences. A pose first block (7 parameters, 6 tangent directions) is compared on its tangent
// columns, and its last column must be zero.
template <int R, int P0, int P1>
void expectJacobiansMatchNumeric(const ceres::CostFunction& cost, const std::vector<std::vector<double>>& params,
                                 bool first_is_pose) {
  double r[R], j0[R * P0], j1[R * P1];
  double* jac[] = {j0, j1};
  const double* ptrs[] = {params[0].data(), params[1].data()};
  ASSERT_TRUE(cost.Evaluate(ptrs, r, jac));
  const Eigen::Map<Eigen::Matrix<double, R, P0, Eigen::RowMajor>> A0(j0);
  const Eigen::Map<Eigen::Matrix<double, R, P1, Eigen::RowMajor>> A1(j1);
  const Eigen::MatrixXd N0 = numericJacobian<R>(cost, params, 0, first_is_pose),
                        N1 = numericJacobian<R>(cost, params, 1, false);
  EXPECT_LT((A0.leftCols(N0.cols()) - N0).norm(), 1e-6 * (1 + N0.norm())) << A0 << "\n" << N0;
  if (first_is_pose) {
    EXPECT_EQ(A0.col(6).norm(), 0.0);
  }
  EXPECT_LT((A1 - N1).norm(), 1e-6 * (1 + N1.norm())) << A1 << "\n" << N1;
}

TEST(ObjectFactors, BoxCostJacobiansMatchNumericOnes) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Isometry3d T_cw = randomPose(rng, 5), T_wo = randomPose(rng, 10);
    const Eigen::Isometry3d meas = randomPose(rng, 10);
    std::vector<std::vector<double>> params{std::vector<double>(7), {0.1 * trial, 1.0, -2.0, 3.0}};
    optimize::poseToParams(T_cw, params[0].data());
    (void)T_wo;
    const objects::ObjectBoxCost cost(meas, T_wo.linear(), 0.3, 0.1, 0.8);
    expectJacobiansMatchNumeric<4, 7, 4>(cost, params, true);
  }
}

TEST(ObjectFactors, BoxCostIsZeroAtTheTruthAndIgnoresAFlippedHeading) {
  std::mt19937 rng(4);
  const Eigen::Isometry3d T_cw = randomPose(rng, 5), T_wo = randomPose(rng, 10);
  std::vector<double> pose(7), node{0, T_wo.translation().x(), T_wo.translation().y(), T_wo.translation().z()};
  optimize::poseToParams(T_cw, pose.data());
  const double* ptrs[] = {pose.data(), node.data()};
  double r[4];
  Eigen::Isometry3d meas = T_cw * T_wo;
  objects::ObjectBoxCost(meas, T_wo.linear(), 0.3, 0.1, 1.0).Evaluate(ptrs, r, nullptr);
  EXPECT_LT(Eigen::Map<Eigen::Vector4d>(r).norm(), 1e-9);
  meas.linear() = meas.linear() * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  objects::ObjectBoxCost(meas, T_wo.linear(), 0.3, 0.1, 1.0).Evaluate(ptrs, r, nullptr);
  EXPECT_LT(std::abs(r[3]), 1e-6) << "front and back confused: no heading error";
}

TEST(ObjectFactors, SurfaceCostJacobiansMatchNumericOnes) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Isometry3d T_wo = randomPose(rng, 10);
    std::vector<std::vector<double>> params{{1.5, -0.5, 12.0}, {-0.2 * trial, 0.5, 1.0, 11.0}};
    const Eigen::Vector3d normal = trial % 2 ? Eigen::Vector3d(0, 0.6, 0.8) : Eigen::Vector3d::Zero();
    const objects::SurfacePointCost cost(Eigen::Vector3d(0.3, -0.2, 0.6), normal, T_wo.linear(), 0.1, 0.7);
    expectJacobiansMatchNumeric<3, 3, 4>(cost, params, false);
  }
}

TEST(SurfaceIndex, NearestIsTheBruteForceNearestWithinTheRadius) {
  const std::vector<Eigen::Vector3d> samples = boxSurface({4.2, 1.8, 1.5}, 0.1);
  const double radius = 0.3;
  const objects::SurfaceIndex index(samples, radius);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-3, 3);
  int found = 0, none = 0;
  for (int q = 0; q < 3000; ++q) {
    const Eigen::Vector3d p(u(rng), u(rng) / 2, u(rng) / 2);
    double best_d = 1e18;
    for (const Eigen::Vector3d& s : samples) best_d = std::min(best_d, (s - p).norm());
    const auto got = index.nearest(p);
    if (best_d < radius) {
      ASSERT_TRUE(got.has_value()) << "query " << q;
      EXPECT_DOUBLE_EQ((samples[*got] - p).norm(), best_d);
      ++found;
    } else if (best_d > radius) {
      EXPECT_FALSE(got.has_value()) << "query " << q << " is " << best_d << " m from the surface";
      ++none;
    }
  }
  EXPECT_GT(found, 300);
  EXPECT_GT(none, 300);
  // Normals: a sample in the middle of the top face points along z, one mid-side along y.
  const auto top = index.nearest({0.05, 0.05, 0.75}), side = index.nearest({0.05, 0.9, 0.05});
  ASSERT_TRUE(top && side);
  EXPECT_NEAR(std::abs(index.normal(*top).z()), 1.0, 1e-9);
  EXPECT_NEAR(std::abs(index.normal(*side).y()), 1.0, 1e-9);
}

// The scene of the object BA test: keyframes 0..4 driving forward; 150 background points seen by
// keyframes 0-3, 40 points on a parked car (surface samples) seen by keyframes 0-3, 60 points seen only by
// keyframes 3 and 4. Keyframe 4 and its 60 points start scaled about keyframe 3's centre (x1.3 baseline:
// 0.3 m): the monocular scale error that reprojection cannot see. Every keyframe has a box of the car.
struct ObjectScene {
  Map map;
  std::vector<KeyFrame*> kfs;
  std::vector<Eigen::Isometry3d> truth;  // T_cw
  Eigen::Isometry3d T_wo = Eigen::Isometry3d::Identity();
  double start_error = 0;
  std::vector<MapPoint*> car_points;

  // kf4_scale: keyframe 4 and the points only it and keyframe 3 see start scaled by this about keyframe 3
  // (1: at the truth). shape_inset: the landmark's surface lies this far inside the car (a fitted shape's
  // error); the map points are on the true surface.
  explicit ObjectScene(const ScalePyramid& pyr, uint64_t seed, double kf4_scale = 1.3, double shape_inset = 0) {
    std::mt19937 rng(static_cast<unsigned>(seed));
    std::normal_distribution<double> pixel(0, 0.5), box_pos(0, 0.03), box_yaw(0, 0.01);
    for (int k = 0; k < 5; ++k) {
      Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
      T_wc.linear() = Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitY()).toRotationMatrix();
      T_wc.translation() = Eigen::Vector3d(0.05 * k, 0, 1.0 * k);
      truth.push_back(T_wc.inverse());
    }
    T_wo.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()).toRotationMatrix() * objects::boxToBody();
    T_wo.translation() = Eigen::Vector3d(3.0, 1.0, 14.0);
    const std::vector<Eigen::Vector3d> surface = boxSurface({4.2, 1.8, 1.5}, 0.1);

    std::uniform_real_distribution<double> ux(-6, 6), uy(-2, 2), uz(8, 30), uz_far(12, 35);
    struct P {
      Eigen::Vector3d world, start;
      int first_kf, last_kf;
      bool car;
    };
    std::vector<P> pts;
    for (int i = 0; i < 150; ++i) {
      const Eigen::Vector3d x(ux(rng), uy(rng), uz(rng));
      pts.push_back({x, x, 0, 3, false});
    }
    for (int i = 0; i < 40; ++i) {
      const Eigen::Vector3d x = T_wo * surface[(i * 97) % surface.size()];
      pts.push_back({x, x, 0, 3, true});
    }
    const double s = kf4_scale;
    const Eigen::Vector3d c3 = truth[3].inverse().translation();
    for (int i = 0; i < 60; ++i) {
      const Eigen::Vector3d x(ux(rng), uy(rng), uz_far(rng));
      pts.push_back({x, c3 + s * (x - c3), 3, 4, false});
    }
    std::vector<Eigen::Isometry3d> start(truth);
    const Eigen::Vector3d c4 = c3 + s * (truth[4].inverse().translation() - c3);
    start[4].translation() = -(start[4].linear() * c4);
    start_error = (c4 - truth[4].inverse().translation()).norm();

    std::vector<std::vector<std::pair<size_t, size_t>>> obs(5);  // per keyframe: (point, keypoint)
    for (int k = 0; k < 5; ++k) {
      auto f = std::make_shared<FeatureSet>();
      f->width = kCam.width;
      f->height = kCam.height;
      for (size_t i = 0; i < pts.size(); ++i) {
        if (k < pts[i].first_kf || k > pts[i].last_kf) continue;
        const Eigen::Vector2d uv =
            test::project(kCam, truth[k], pts[i].world) + Eigen::Vector2d(pixel(rng), pixel(rng));
        obs[k].emplace_back(i, f->keypoints.size());
        f->keypoints.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f, 0.f, 1.f, 0);
      }
      f->descriptors = cv::Mat(static_cast<int>(f->keypoints.size()), 32, CV_8U, cv::Scalar(0));
      f->labels.assign(f->keypoints.size(), 0);
      f->colours.assign(f->keypoints.size(), cv::Vec3b(0, 0, 0));
      Eigen::Isometry3d T_cam_object = truth[k] * T_wo;
      T_cam_object.translation() += Eigen::Vector3d(box_pos(rng), box_pos(rng), box_pos(rng));
      T_cam_object.linear() = T_cam_object.linear() * Eigen::AngleAxisd(box_yaw(rng), Eigen::Vector3d::UnitZ());
      ObjectBox box;
      box.object_id = 7;
      box.parked = true;
      box.T_cam_box = T_cam_object;
      box.T_cam_box.linear() = T_cam_object.linear() * objects::boxToBody().transpose();
      box.size = Eigen::Vector3d(4.2, 1.5, 1.8);
      f->object_boxes.push_back(box);
      f->buildGrid();
      Frame frame(k, 0.1 * k, f);
      frame.T_cw = start[k];
      kfs.push_back(map.createKeyFrame(frame, kCam, pyr));
    }
    map.setOrigin(kfs[0]);
    std::vector<MapPoint*> mps;
    for (const P& p : pts) {
      MapPoint* mp = map.createMapPoint(p.start, kfs[p.first_kf]);
      if (p.car) {
        mp->trusted = true;
        mp->object_id = 7;
        car_points.push_back(mp);
      }
      mps.push_back(mp);
    }
    for (int k = 0; k < 5; ++k)
      for (auto [i, idx] : obs[k]) {
        kfs[k]->addPoint(mps[i], idx);
        mps[i]->addObservation(kfs[k], idx);
      }
    for (MapPoint* mp : mps) mp->updateNormalAndDepth();
    for (KeyFrame* kf : kfs) kf->updateConnections();

    // The reconstructor's landmark: 0.1 m and 2 degrees off.
    ObjectLandmark l;
    l.id = 7;
    l.confidence = 0.9;
    l.T_world_object = T_wo;
    l.T_world_object.translation() += Eigen::Vector3d(0.08, 0, -0.06);
    l.T_world_object.linear() = l.T_world_object.linear() * Eigen::AngleAxisd(0.035, Eigen::Vector3d::UnitZ());
    l.dimensions = Eigen::Vector3d(4.2, 1.8, 1.5);
    l.points_object =
        shape_inset > 0 ? boxSurface(Eigen::Vector3d(4.2, 1.8, 1.5).array() - 2 * shape_inset, 0.1) : surface;
    map.objects().add(l, map.lastKeyFrameId());
  }

  double error(int k) const { return (kfs[k]->centre() - truth[k].inverse().translation()).norm(); }
  // Reprojection alone leaves keyframe 4 where the wrong baseline put it, up to a drift along that weakly
  // seen direction whose size follows the compiler's rounding (0.27-0.30 of the 0.30 m start error with
  // gcc's Release build, 0.24-0.29 m with clang's sanitised one): still wrong means more than half of it.
  bool stillWrong(int k) const { return error(k) > start_error / 2; }
};

TEST(ObjectBundleAdjustment, PullsAKeyframeWithAWrongBaselineBack) {
  const ScalePyramid pyr(8, 1.2);
  optimize::BundleAdjustmentOptions without;
  optimize::BundleAdjustmentOptions with;
  with.objects.enabled = true;
  for (uint64_t seed : {1, 2, 3}) {
    ObjectScene a(pyr, seed), b(pyr, seed);
    ASSERT_NEAR(a.start_error, 0.3, 0.01);
    const auto ra = optimize::localBundleAdjustment(a.kfs[4], a.map, without);
    const auto rb = optimize::localBundleAdjustment(b.kfs[4], b.map, with);
    EXPECT_EQ(ra.keyframes, 2);  // keyframes 3 and 4 move, 0-2 are fixed
    EXPECT_EQ(ra.fixed_keyframes, 3);
    EXPECT_EQ(ra.object_nodes, 0);
    EXPECT_EQ(rb.object_nodes, 1);
    EXPECT_EQ(rb.object_box_factors, 5);
    EXPECT_EQ(rb.object_surface_factors, 40);
    std::printf("seed %lu: keyframe 4 off by %.3f m at the start, %.3f m after BA without objects, %.3f m with\n",
                static_cast<unsigned long>(seed), a.start_error, a.error(4), b.error(4));
    EXPECT_TRUE(a.stillWrong(4)) << "reprojection alone cannot see the baseline";
    EXPECT_LT(b.error(4), a.start_error / 5) << "the car's box in keyframe 4 pulls it back";
    const ObjectLandmark l = b.map.objects().landmarks().at(0);
    EXPECT_LT((l.T_world_object.translation() - b.T_wo.translation()).norm(), 0.08);
    EXPECT_LT(Eigen::AngleAxisd(l.T_world_object.linear().transpose() * b.T_wo.linear()).angle(), 0.03);
  }
}

// A fitted shape is never exact (the reconstructor's cars are about 0.1 m off in Chamfer distance; on
// whole runs the map points lay 0.1-0.15 m outside them on average) and its error is common to every point
// on the car, so the car's points together count as one surface observation (the paper's 1/|P|). Weighed
// one observation each, a hundred points outweighed every box of the car and pulled the map's scale away
// (docs/object-ba.md). Here the landmark's surface lies 0.1 m inside the car and the points on the true
// surface: the surface factors' total cost is the same with 20 of the car's points as with all 40.
TEST(ObjectBundleAdjustment, ACarsPointsCountAsOneSurfaceObservation) {
  const ScalePyramid pyr(8, 1.2);
  ObjectScene scene(pyr, 1, 1.0, 0.1);
  objects::ObjectFactorOptions options;
  options.enabled = true;
  options.use_boxes = false;
  std::map<KeyFrame*, double*, IdLess<KeyFrame>> poses;
  std::set<const KeyFrame*> moving(scene.kfs.begin(), scene.kfs.end());
  std::vector<std::array<double, 3>> storage(scene.car_points.size());
  const auto surfaceCost = [&](size_t n_points) {
    std::map<MapPoint*, double*, IdLess<MapPoint>> positions;
    for (size_t i = 0; i < n_points; ++i) {
      MapPoint* mp = scene.car_points[i];
      for (int k = 0; k < 3; ++k) storage[i][k] = mp->position[k];
      positions[mp] = storage[i].data();
    }
    const auto P = objects::buildObjectProblem(scene.map.objects(), poses, moving, positions, options);
    EXPECT_EQ(P->surface_factors, static_cast<int>(n_points));
    double cost = 0;
    for (const auto& f : P->factors) {
      double r[3];
      const double* params[] = {f.blocks[0], f.blocks[1]};
      f.cost->Evaluate(params, r, nullptr);
      cost += r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    }
    return cost;
  };
  const double half = surfaceCost(20), all = surfaceCost(40);
  // About (0.1 m / surface_sigma)^2 x confidence either way; points near an edge are nearer a sample.
  std::printf("surface cost of the car: %.3f with 20 points, %.3f with 40\n", half, all);
  EXPECT_GT(all, 0.3);
  EXPECT_NEAR(all / half, 1.0, 0.25);
}

TEST(ObjectBundleAdjustment, ZeroConfidenceOrNoLandmarkAddsNothing) {
  const ScalePyramid pyr(8, 1.2);
  optimize::BundleAdjustmentOptions with;
  with.objects.enabled = true;
  ObjectScene a(pyr, 1);
  ObjectLandmark l = a.map.objects().landmarks().at(0);
  l.confidence = 0;
  a.map.objects().add(l, 0);
  EXPECT_EQ(optimize::localBundleAdjustment(a.kfs[4], a.map, with).object_nodes, 0);
  ObjectScene b(pyr, 1);
  b.map.objects().erase(7, b.map.lastKeyFrameId());
  const auto r = optimize::localBundleAdjustment(b.kfs[4], b.map, with);
  EXPECT_EQ(r.object_nodes, 0);
  EXPECT_TRUE(b.stillWrong(4));
}

// Issue 14: a metric map's scale held by the parked car's box centres alone (no landmark, no shape): one
// anchor for the car, measured by the boxes of all five keyframes, pulls keyframe 4 back as the landmark does.
TEST(ParkedCarAnchors, PullAKeyframeWithAWrongBaselineBack) {
  const ScalePyramid pyr(8, 1.2);
  optimize::BundleAdjustmentOptions anchors;
  anchors.object_range_sigma = 0.05;  // the scene's boxes have 3 cm noise
  anchors.object_range_sigma_per_m = 0;
  optimize::BundleAdjustmentOptions none = anchors;
  none.object_anchors = false;
  for (uint64_t seed : {1, 2, 3}) {
    ObjectScene a(pyr, seed), b(pyr, seed);
    a.map.objects().erase(7, -1);  // no landmark: the boxes alone
    b.map.objects().erase(7, -1);
    const auto ra = optimize::localBundleAdjustment(a.kfs[4], a.map, none);
    const auto rb = optimize::localBundleAdjustment(b.kfs[4], b.map, anchors);
    EXPECT_EQ(ra.object_anchor_residuals, 0);
    EXPECT_EQ(rb.object_anchor_residuals, 5) << "one box a keyframe, fixed ones included";
    EXPECT_TRUE(a.stillWrong(4)) << "reprojection alone cannot see the baseline";
    // The boxes' centres carry 3 cm of noise: they take back at least three quarters of the error (0.06 m
    // left on one seed with clang).
    EXPECT_LT(b.error(4), b.start_error / 4) << "the car's box in keyframe 4 pulls it back";
  }
  // Boxes from before the car was called moving no longer count: they belong to where it was parked then.
  ObjectScene c(pyr, 1);
  c.map.objects().erase(7, c.map.lastKeyFrameId());
  EXPECT_EQ(optimize::localBundleAdjustment(c.kfs[4], c.map, anchors).object_anchor_residuals, 0);
  // A car that is an object node of the BA has its boxes there (camera-object factors), not twice.
  ObjectScene d(pyr, 1);
  optimize::BundleAdjustmentOptions both = anchors;
  both.objects.enabled = true;
  const auto rd = optimize::localBundleAdjustment(d.kfs[4], d.map, both);
  EXPECT_EQ(rd.object_box_factors, 5);
  EXPECT_EQ(rd.object_anchor_residuals, 0);
}

// After a loop correction the global BA keeps the parked cars' terms that local BA has on a metric map
// (LocalMapper::metricTerms, LoopOptions::global_ba_objects): without them it leaves keyframe 4's wrong
// baseline where it is, as local BA does; the car's landmark (object_landmarks: ba) or, without one, the
// anchor on its boxes pulls it back.
TEST(ObjectBundleAdjustment, GlobalBaKeepsTheParkedCarsTerms) {
  const ScalePyramid pyr(8, 1.2);
  const optimize::BundleAdjustmentOptions plain = optimize::plainOptions(optimize::BaSolver::SchurLm);
  optimize::BundleAdjustmentOptions landmark = plain, anchor = plain;
  landmark.objects.enabled = true;
  anchor.object_range_sigma = 0.05;  // the scene's boxes have 3 cm noise
  anchor.object_range_sigma_per_m = 0;
  for (uint64_t seed : {1, 2, 3}) {
    ObjectScene a(pyr, seed), b(pyr, seed), c(pyr, seed);
    c.map.objects().erase(7, -1);  // no landmark: the boxes alone
    const Eigen::Isometry3d origin = a.kfs[0]->T_cw;
    const auto ra = optimize::globalBundleAdjustment(a.map, 10, plain);
    const auto rb = optimize::globalBundleAdjustment(b.map, 10, landmark);
    const auto rc = optimize::globalBundleAdjustment(c.map, 10, anchor);
    EXPECT_EQ(ra.keyframes, 5);
    EXPECT_EQ(ra.object_nodes + ra.object_anchor_residuals, 0);
    EXPECT_EQ(rb.object_nodes, 1);
    EXPECT_EQ(rb.object_box_factors, 5);
    EXPECT_EQ(rb.object_anchor_residuals, 0) << "a car that is a node has its boxes there, not twice";
    EXPECT_EQ(rc.object_anchor_residuals, 5);
    std::printf(
        "seed %lu: keyframe 4 off by %.3f m at the start; after global BA %.3f m plain, %.3f m with the "
        "landmark, %.3f m with the anchor\n",
        static_cast<unsigned long>(seed), a.start_error, a.error(4), b.error(4), c.error(4));
    EXPECT_TRUE(a.stillWrong(4)) << "reprojection alone cannot see the baseline";
    // Every keyframe but the origin moves here, so the box of keyframe 4 pulls against more freedom than in
    // local BA: at least two thirds of the error taken back (0.017-0.086 m left of 0.30 with gcc).
    EXPECT_LT(b.error(4), b.start_error / 3);
    EXPECT_LT(c.error(4), c.start_error / 3);
    EXPECT_EQ(b.kfs[0]->T_cw.matrix(), origin.matrix()) << "the origin keyframe stays fixed";
  }
}

ObjectLandmark carLandmark(int64_t id) {
  ObjectLandmark l;
  l.id = id;
  l.confidence = 0.75;
  l.T_world_object.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix() * objects::boxToBody();
  l.T_world_object.translation() = Eigen::Vector3d(1.0 + id, 1.2, 10.0);
  l.dimensions = Eigen::Vector3d(4.0, 1.7, 1.4);
  l.points_object = boxSurface(l.dimensions, 0.5);
  return l;
}

// In every mapping mode: with a mapping thread the changes wait for an idle mapper and are applied in
// call order (a drop then a re-add of the same id leaves it there; an add then a drop does not).
TEST(ObjectLandmarks, DropObjectRemovesTheLandmarkInEveryMappingMode) {
  for (int mode = 0; mode < 3; ++mode) {
    Options o;
    o.threading.threaded_mapping = mode == 1;
    o.threading.concurrent_mapping = mode == 2;
    OrbSlam slam(kCam, o);
    slam.addObjectLandmarks({carLandmark(7), carLandmark(8)});
    ASSERT_EQ(slam.objectLandmarks().size(), 2u) << mode;
    slam.dropObject(7);
    const auto left = slam.objectLandmarks();
    ASSERT_EQ(left.size(), 1u) << mode;
    EXPECT_EQ(left[0].id, 8) << mode;
    slam.dropObject(8);
    slam.addObjectLandmarks({carLandmark(8), carLandmark(9)});
    slam.dropObject(9);
    const auto last = slam.objectLandmarks();
    ASSERT_EQ(last.size(), 1u) << mode;
    EXPECT_EQ(last[0].id, 8) << mode;
  }
}

// A loop correction moves each landmark rigidly with the keyframe it was last added at; one whose
// keyframe has no motion (or a non-finite one) stays.
TEST(ObjectLandmarks, FollowTheKeyframeTheyWereAddedAt) {
  objects::ObjectStore store;
  store.add(carLandmark(1), 3);
  store.add(carLandmark(2), 7);
  store.add(carLandmark(3), 9);
  const std::vector<ObjectLandmark> before = store.landmarks();
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  motion.translation() = Eigen::Vector3d(1.5, 0, -2.0);
  Eigen::Isometry3d broken = motion;
  broken.translation().x() = std::numeric_limits<double>::quiet_NaN();
  store.followKeyFrames([&](long kf_id) -> std::optional<Eigen::Isometry3d> {
    if (kf_id == 3) return motion;
    if (kf_id == 9) return broken;
    return std::nullopt;
  });
  const std::vector<ObjectLandmark> after = store.landmarks();
  EXPECT_TRUE(after[0].T_world_object.isApprox(motion * before[0].T_world_object, 1e-12));
  EXPECT_TRUE(after[1].T_world_object.isApprox(before[1].T_world_object, 1e-12));
  EXPECT_TRUE(after[2].T_world_object.isApprox(before[2].T_world_object, 1e-12));
  EXPECT_EQ(after[0].dimensions, before[0].dimensions) << "a rigid motion: the car keeps its size";
  EXPECT_EQ(after[0].points_object, before[0].points_object);
}

TEST(ObjectLandmarks, NonFiniteInputIsLeftOut) {
  OrbSlam slam(kCam, Options{});
  ObjectLandmark bad = carLandmark(7), partly = carLandmark(8);
  bad.T_world_object.translation().x() = std::nan("");
  const size_t samples = partly.points_object.size();
  partly.points_object[3] = Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0);
  slam.addObjectLandmarks({bad, partly});
  const auto kept = slam.objectLandmarks();
  ASSERT_EQ(kept.size(), 1u) << "a landmark without a finite pose is not kept";
  EXPECT_EQ(kept[0].id, 8);
  EXPECT_EQ(kept[0].points_object.size(), samples - 1) << "the non-finite sample is dropped";
}

TEST(ObjectLandmarks, SurviveAMapFileRoundTrip) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("beslam_objba_" + std::to_string(::getpid()) + ".map")).string();
  {
    OrbSlam slam(kCam, Options{});
    slam.addObjectLandmarks({carLandmark(7), carLandmark(8)});
    slam.saveMap(path);
  }
  OrbSlam loaded(kCam, Options{});
  loaded.loadMap(path);
  std::filesystem::remove(path);
  const auto l = loaded.objectLandmarks();
  ASSERT_EQ(l.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const ObjectLandmark want = carLandmark(7 + i);
    EXPECT_EQ(l[i].id, want.id);
    EXPECT_EQ(l[i].confidence, want.confidence);
    EXPECT_EQ(l[i].T_world_object.matrix(), want.T_world_object.matrix());
    EXPECT_EQ(l[i].dimensions, want.dimensions);
    ASSERT_EQ(l[i].points_object.size(), want.points_object.size());
    EXPECT_EQ(l[i].points_object.back(), want.points_object.back());
  }
}

// `off` (the default) with landmarks given, and `ba` on a map that is not metric (landmarks are metric,
// so they stay out), track the corridor exactly as a run that never heard of objects.
TEST(ObjectLandmarks, OffAndNonMetricRunsAreByteIdenticalToNoObjects) {
  const test::CorridorWorld world;
  std::vector<cv::Mat> images;
  for (int i = 0; i < 20; ++i) images.push_back(world.render(i));
  auto run = [&](ObjectLandmarkMode mode, bool landmarks) {
    Options o;
    o.extractor.features = 1000;
    o.object_landmarks.mode = mode;
    OrbSlam slam(world.camera(), o);
    ObjectBox box;  // a parked car's box every frame (not on the image)
    box.object_id = 7;
    box.parked = true;
    box.T_cam_box.translation() = Eigen::Vector3d(2, 1, 12);
    for (int i = 0; i < 20; ++i) {
      slam.track(images[i], cv::Mat(), 0.1 * i, i, {box});
      if (landmarks && i == 5) slam.addObjectLandmarks({carLandmark(7)});
    }
    slam.finish();
    return slam.trajectory();
  };
  const auto reference = run(ObjectLandmarkMode::Off, false);
  ASSERT_GT(reference.size(), 10u);
  for (auto [mode, landmarks] : {std::pair{ObjectLandmarkMode::Off, true}, std::pair{ObjectLandmarkMode::BA, true}}) {
    const auto t = run(mode, landmarks);
    ASSERT_EQ(t.size(), reference.size());
    for (size_t i = 0; i < t.size(); ++i) {
      EXPECT_EQ(t[i].frame_index, reference[i].frame_index);
      EXPECT_EQ(t[i].T_world_cam.matrix(), reference[i].T_world_cam.matrix());
    }
  }
}

// The whole path on the rendered corridor with metric scale (camera 1.5 m over the floor): a 8 x 2.5 m
// patch of the left wall labelled as parked object 7, its exact box in every frame, and, once the map is
// metric, its landmark (samples of the patch) placed with the frame's tracked pose. With `ba` the
// keyframes' boxes and the patch's map points enter local BA, the same with threaded mapping.
TEST(ObjectLandmarks, EnterLocalBaOfAMetricCorridorRun) {
  const test::CorridorWorld world;
  const Camera cam = world.camera();
  constexpr int kFrames = 40;
  Eigen::Isometry3d T_gt_object = Eigen::Isometry3d::Identity();  // body x along the wall, z up
  T_gt_object.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  T_gt_object.translation() = Eigen::Vector3d(-3, -0.25, 12);
  const double y0 = -1.5, y1 = 1.0, z0 = 8, z1 = 16;
  ObjectLandmark truth;
  truth.id = 7;
  truth.confidence = 1.0;
  truth.dimensions = Eigen::Vector3d(z1 - z0, 0.2, y1 - y0);
  for (double y = y0; y <= y1 + 1e-9; y += 0.1)
    for (double z = z0; z <= z1 + 1e-9; z += 0.1)
      truth.points_object.push_back(T_gt_object.inverse() * Eigen::Vector3d(-3, y, z));
  std::vector<cv::Mat> images, masks;
  for (int i = 0; i < kFrames; ++i) {
    images.push_back(world.render(i));
    cv::Mat mask(cam.height, cam.width, CV_16UC1, cv::Scalar(0));
    const Eigen::Isometry3d T_wc = world.pose(i);
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        const Eigen::Vector3d d = T_wc.linear() * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1);
        if (d.x() >= -1e-9) continue;
        const Eigen::Vector3d p = T_wc.translation() + d * ((-3 - T_wc.translation().x()) / d.x());
        if (p.y() > y0 && p.y() < y1 && p.z() > z0 && p.z() < z1) mask.at<uint16_t>(v, u) = 1007;
      }
    masks.push_back(mask);
  }
  struct Run {
    double ape = 0;
    int max_factors = 0, landmarks = 0;
    int64_t added_at = -1;
    std::vector<ObjectLandmark> final;
    Eigen::Isometry3d T_slam_gt = Eigen::Isometry3d::Identity();
  };
  auto run = [&](ObjectLandmarkMode mode, bool threaded) {
    Options o;
    o.threading.threaded_mapping = threaded;
    o.extractor.features = 1000;
    o.scale.metric_scale = true;
    o.scale.camera_height = 1.5;
    o.object_landmarks.mode = mode;
    OrbSlam slam(cam, o);
    Run out;
    for (int i = 0; i < kFrames; ++i) {
      ObjectBox box;
      box.object_id = 7;
      box.parked = true;
      box.T_cam_box = world.pose(i).inverse() * T_gt_object;
      box.T_cam_box.linear() = box.T_cam_box.linear() * objects::boxToBody().transpose();
      box.size = Eigen::Vector3d(truth.dimensions.x(), truth.dimensions.z(), truth.dimensions.y());
      const TrackResult r = slam.track(images[i], masks[i], 0.1 * i, i, {box});
      out.max_factors = std::max(out.max_factors, r.object_factors);
      out.landmarks = r.object_landmarks;
      if (r.world_is_metric && r.state == TrackingState::Ok && out.added_at < 0) {
        out.T_slam_gt = r.T_world_cam * world.pose(i).inverse();
        ObjectLandmark l = truth;
        l.T_world_object = out.T_slam_gt * T_gt_object;
        slam.addObjectLandmarks({l});
        out.added_at = i;
      }
    }
    slam.finish();
    std::vector<Eigen::Vector3d> est, gt;
    for (const FramePose& p : slam.trajectory()) {
      est.push_back(p.T_world_cam.translation());
      gt.push_back(world.pose(static_cast<int>(p.frame_index)).translation());
    }
    out.ape = formats::positionError(est, gt).rmse;
    out.final = slam.objectLandmarks();
    return out;
  };
  const Run off = run(ObjectLandmarkMode::Off, false), ba = run(ObjectLandmarkMode::BA, false);
  const Run threaded = run(ObjectLandmarkMode::BA, true);
  std::printf(
      "corridor, metric: landmark added at frame %ld (off) / %ld (ba); APE off %.4f m, ba %.4f m; "
      "object factors per local BA up to %d\n",
      static_cast<long>(off.added_at), static_cast<long>(ba.added_at), off.ape, ba.ape, ba.max_factors);
  ASSERT_GE(ba.added_at, 0) << "the corridor run became metric";
  EXPECT_EQ(off.max_factors, 0);
  EXPECT_GT(ba.max_factors, 10);
  EXPECT_EQ(ba.landmarks, 1);
  ASSERT_EQ(ba.final.size(), 1u);
  EXPECT_LT(ba.ape, 1.5 * off.ape + 0.02) << "objects do not spoil the run";
  EXPECT_EQ(threaded.ape, ba.ape) << "threaded mapping gives the same run";
  ASSERT_EQ(threaded.final.size(), 1u);
  EXPECT_EQ(threaded.final[0].T_world_object.matrix(), ba.final[0].T_world_object.matrix());
}

}  // namespace
}  // namespace beslam::orb
