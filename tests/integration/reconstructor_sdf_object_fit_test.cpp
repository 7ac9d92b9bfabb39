// fitObject with the shipped prior: cars recovered from simulated LiDAR points and from sparse noisy map
// points after a perturbed start, and bad observations rejected without a crash.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "beslam/shape_prior/car_set.hpp"
#include "fit/object_fit.hpp"
#include "fit/render_depth.hpp"
#include "fit/silhouette.hpp"
#include "shipped_prior.hpp"

using namespace beslam::recon;

namespace {

struct Scenario {
  tools::Car car;
  Eigen::Isometry3d T_world_obj, T_init;
  fit::FitObservations obs;
};

// A held-out car at a random place and heading, seen from `range` metres at `bearing` (object frame),
// n points with noise; the start pose is 0.5 m and 10 degrees off.
Scenario scenario(int index, int n, double noise, double bearing, double range) {
  Scenario s;
  s.car = tools::heldOutCars(index + 1, 21)[index];
  const Eigen::Vector3d size = s.car.body.size;
  const Eigen::Vector3d sensor(range * std::cos(bearing), range * std::sin(bearing), 1.7 - size.z() / 2);
  const auto pts = tools::visibleSurfacePoints(s.car.body.mesh, sensor, n, noise, 100 + index);
  s.T_world_obj = Eigen::Isometry3d::Identity();
  s.T_world_obj.linear() = Eigen::AngleAxisd(0.7 + index, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  s.T_world_obj.translation() = Eigen::Vector3d(12 - 3 * index, 5 + index, size.z() / 2);
  for (const auto& p : pts) s.obs.p_world.push_back(s.T_world_obj * p);
  s.T_init = s.T_world_obj;
  const double a = 1.3 * index;
  s.T_init.translation() += 0.5 * Eigen::Vector3d(std::cos(a), std::sin(a), 0);
  const double yaw = (index % 2 ? 10.0 : -10.0) * M_PI / 180;
  s.T_init.linear() = s.T_world_obj.linear() * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return s;
}

struct Errors {
  double centre, yaw_deg, chamfer;
};

Errors errors(const Scenario& s, const fit::FitResult& r) {
  Errors e;
  e.centre = (r.T_world_obj.translation() - s.T_world_obj.translation()).norm();
  const Eigen::Matrix3d dR = s.T_world_obj.linear().transpose() * r.T_world_obj.linear();
  e.yaw_deg = std::abs(std::atan2(dR(1, 0), dR(0, 0))) * 180 / M_PI;
  shape::Mesh m = test::shippedPrior().mesh(r.code, r.size);
  const Eigen::Isometry3d T = s.T_world_obj.inverse() * r.T_world_obj;
  for (auto& v : m.vertices) v = T * v;
  e.chamfer = shape::chamferDistance(m, s.car.body.mesh, 300, 9);
  return e;
}

// fitObject with the shipped prior from the scenario's start pose, at `size`, from the mean shape.
fit::FitResult fitFromStart(const Scenario& s, const Eigen::Vector3d& size,
                            const fit::FitOptions& options = fit::FitOptions()) {
  return fit::fitObject(test::shippedPrior(), s.T_init, size, Eigen::VectorXd::Zero(test::shippedPrior().dimensions()),
                        s.obs, options);
}

// Expects car i's errors below `bound` (centre in metres, yaw in degrees, chamfer in metres).
void expectErrorsBelow(const Errors& e, const Errors& bound, int i, const Scenario& s) {
  EXPECT_LT(e.centre, bound.centre) << "car " << i << " " << s.car.shape;
  EXPECT_LT(e.yaw_deg, bound.yaw_deg) << "car " << i << " " << s.car.shape;
  EXPECT_LT(e.chamfer, bound.chamfer) << "car " << i << " " << s.car.shape;
}

// The gradient checks' Jet: partials by the ray's origin (0-2), its direction (3-5) and the code (6 on, up to 8).
using RayJet = ceres::Jet<double, 14>;
constexpr double kCheckedCarSize[3] = {4.5, 1.8, 1.5};  // the car the gradient checks query

// A random code of the prior: each value uniform within one standard deviation.
std::vector<double> randomCode(const shape::ShapePrior& prior, shape::Random& rng) {
  std::vector<double> z(prior.dimensions());
  for (int k = 0; k < prior.dimensions(); ++k) z[k] = rng.uniform(-1, 1) * prior.codeStd()(k);
  return z;
}

// A ray query's Jet inputs: origin and direction (differentiated), the car's size (constant) and the code.
struct RayJets {
  RayJet origin[3], direction[3], size[3], code[8];
  RayJets(const Eigen::Vector3d& o, const Eigen::Vector3d& u, const std::vector<double>& z) {
    for (int a = 0; a < 3; ++a)
      origin[a] = RayJet(o(a), a), direction[a] = RayJet(u(a), 3 + a), size[a] = RayJet(kCheckedCarSize[a]);
    for (size_t k = 0; k < z.size(); ++k) code[k] = RayJet(z[k], 6 + static_cast<int>(k));
  }
};

}  // namespace

TEST(ObjectFit, RecoversACarFromLidarPoints) {
  const double bearings[] = {0.6, 2.5, -1.2, -2.2};
  for (int i = 0; i < 4; ++i) {
    const Scenario s = scenario(i, 200, 0.02, bearings[i], 8.0);
    ASSERT_GE(s.obs.p_world.size(), 150u);
    const fit::FitResult r = fitFromStart(s, s.car.body.size);
    ASSERT_TRUE(r.ok) << r.why;
    const Errors e = errors(s, r);
    expectErrorsBelow(e, {0.15, 5.0, 0.10}, i, s);
    EXPECT_GT(r.inliers, static_cast<int>(0.8 * s.obs.p_world.size()));
    EXPECT_LT(r.rms_m, 0.06);
  }
}

TEST(ObjectFit, RecoversACarFromSparseMapPoints) {
  // 30-80 points with 5 cm noise: fewer and noisier points leave the shape code and the translation
  // along the seen faces less constrained; 5 cm noise alone moves a 30-point centroid by about 1 cm,
  // the rest is shape/pose trade-off. `beslam shape-prior eval --fit` measures a centre error of 4 cm
  // median and 6 cm at 90 % for 50 points; bounds 0.30 m, 8 deg, 0.15 m (LiDAR: 0.15 m, 5 deg, 0.10 m).
  const int counts[] = {30, 50, 80, 40};
  const double bearings[] = {0.9, -2.4, 2.0, -0.5};
  fit::FitOptions opt;
  opt.sigma_m = 0.05;
  opt.huber_m = 0.10;
  for (int i = 0; i < 4; ++i) {
    const Scenario s = scenario(i + 4, counts[i], 0.05, bearings[i], 9.0);
    const fit::FitResult r = fitFromStart(s, s.car.body.size, opt);
    ASSERT_TRUE(r.ok) << r.why;
    const Errors e = errors(s, r);
    expectErrorsBelow(e, {0.30, 8.0, 0.15}, i, s);
  }
}

TEST(ObjectFit, FullPoseAndSizeOptionsStillConverge) {
  const Scenario s = scenario(1, 200, 0.02, 0.5, 7.0);
  fit::FitOptions opt;
  opt.yaw_only = false;
  opt.fit_size = true;
  const Eigen::Vector3d size0 = s.car.body.size.cwiseProduct(Eigen::Vector3d(1.05, 0.97, 1.04));
  const fit::FitResult r = fitFromStart(s, size0, opt);
  ASSERT_TRUE(r.ok) << r.why;
  const Errors e = errors(s, r);
  EXPECT_LT(e.centre, 0.2);
  EXPECT_LT(e.yaw_deg, 5.0);
  EXPECT_LT((r.size - s.car.body.size).cwiseAbs().maxCoeff(), (size0 - s.car.body.size).cwiseAbs().maxCoeff() + 0.05);
}

TEST(ObjectFit, BadObservationsGiveAClearErrorNotACrash) {
  const auto& prior = test::shippedPrior();
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(prior.dimensions());
  const Eigen::Vector3d size(4.5, 1.8, 1.5);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const fit::FitOptions opt;
  fit::FitObservations obs;
  auto why = [&](const fit::FitObservations& o, const Eigen::Vector3d& sz = Eigen::Vector3d(4.5, 1.8, 1.5),
                 const Eigen::VectorXd& code = Eigen::VectorXd()) {
    const fit::FitResult r = fit::fitObject(prior, T, sz, code, o, opt);
    EXPECT_FALSE(r.ok);
    EXPECT_TRUE(r.T_world_obj.isApprox(T));
    return r.why;
  };
  EXPECT_EQ(why(obs), "no surface observations");
  for (int i = 0; i < 10; ++i) obs.p_world.emplace_back(2.25, 0.1 * i, 0.0);
  obs.p_world[3].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(why(obs), "observation 3 is not finite");
  obs.p_world[3].y() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(why(obs), "observation 3 is not finite");
  obs.p_world[3].y() = 0.3;
  obs.weight.assign(10, 1.0);
  obs.weight[5] = 0;
  EXPECT_EQ(why(obs), "weight 5 is outside (0, 1]");
  obs.weight.resize(3);
  EXPECT_EQ(why(obs), "3 weights for 10 observations");
  obs.weight.clear();
  EXPECT_EQ(why(obs, Eigen::Vector3d(4.5, 0, 1.5)), "size must be positive");
  EXPECT_NE(why(obs, size, Eigen::VectorXd::Zero(prior.dimensions() + 1)).find("initial code"), std::string::npos);
  fit::FitObservations with_ray = obs;
  with_ray.rays.push_back({Eigen::Vector3d(10, 0, 0), Eigen::Vector3d(-1, 0, 0), -2.0, 1.0});
  EXPECT_EQ(why(with_ray), "ray 0 is not finite, has no positive depth or no unit direction");
  with_ray.rays[0].depth_m = 7.75;
  with_ray.rays[0].direction_world = Eigen::Vector3d(-2, 0, 0);
  EXPECT_EQ(why(with_ray), "ray 0 is not finite, has no positive depth or no unit direction");
  fit::FitObservations with_silhouette = obs;
  with_silhouette.silhouette.push_back({Eigen::Vector3d(10, 0, 0), Eigen::Vector3d(-1, 0.5, 0), true, 1.0});
  EXPECT_EQ(why(with_silhouette), "silhouette ray 0 is not finite or has no unit direction");
  with_silhouette.silhouette[0].direction_world = Eigen::Vector3d(-1, 0, 0);
  with_silhouette.silhouette[0].weight = 1.5;
  EXPECT_EQ(why(with_silhouette), "silhouette ray 0 weight is outside (0, 1]");
  fit::FitObservations few;
  few.p_world.assign(3, Eigen::Vector3d(2.25, 0, 0));
  EXPECT_EQ(why(few), "fewer than 4 surface observations");
  EXPECT_TRUE(fit::fitObject(prior, T, size, z, obs, opt).ok);  // the same points, all finite
}

TEST(RenderDepth, AutodiffGradientMatchesNumeric) {
  const auto& prior = test::shippedPrior();
  const int K = prior.dimensions();
  ASSERT_LE(K, 8);
  shape::Random rng(2);
  int hits = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const double bearing = rng.uniform(-M_PI, M_PI);
    const Eigen::Vector3d o(8 * std::cos(bearing), 8 * std::sin(bearing), 0.9);
    const Eigen::Vector3d target(rng.uniform(-1.8, 1.8), rng.uniform(-0.6, 0.6), rng.uniform(-0.5, 0.5));
    const Eigen::Vector3d u = (target - o).normalized();
    const std::vector<double> z = randomCode(prior, rng);
    auto render = [&](const Eigen::Vector3d& oo, const Eigen::Vector3d& uu, const std::vector<double>& zz, double* t) {
      const double ov[3] = {oo.x(), oo.y(), oo.z()}, uv[3] = {uu.x(), uu.y(), uu.z()};
      return fit::renderDepth(prior, ov, uv, kCheckedCarSize, zz.data(), t);
    };
    double t0;
    if (!render(o, u, z, &t0)) continue;
    const RayJets in(o, u, z);
    RayJet tj;
    ASSERT_TRUE(fit::renderDepth(prior, in.origin, in.direction, in.size, in.code, &tj));
    EXPECT_NEAR(tj.a, t0, 1e-6);
    const double h = 1e-5;
    for (int a = 0; a < 3; ++a) {
      double tp, tm;
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(a) * h;
      if (!render(o + e, u, z, &tp) || !render(o - e, u, z, &tm)) continue;
      EXPECT_NEAR(tj.v[a], (tp - tm) / (2 * h), 2e-3) << "trial " << trial << " origin " << a;
      if (!render(o, u + e, z, &tp) || !render(o, u - e, z, &tm)) continue;
      EXPECT_NEAR(tj.v[3 + a], (tp - tm) / (2 * h), 2e-2 * std::max(1.0, std::abs(tj.v[3 + a])))
          << "trial " << trial << " direction " << a;
    }
    for (int k = 0; k < K; ++k) {
      std::vector<double> zp = z, zm = z;
      zp[k] += h, zm[k] -= h;
      double tp, tm;
      if (!render(o, u, zp, &tp) || !render(o, u, zm, &tm)) continue;
      EXPECT_NEAR(tj.v[6 + k], (tp - tm) / (2 * h), 2e-3) << "trial " << trial << " code " << k;
    }
    ++hits;
  }
  EXPECT_GE(hits, 20);
}

TEST(ObjectFit, RecoversACarFromADepthMap) {
  // A 24 x 12 pixel patch of a depth map over the car (rays that hit it: the mask), 2 cm depth noise,
  // no points: the rendering term alone.
  for (int i = 0; i < 2; ++i) {
    Scenario s = scenario(8 + i, 0, 0.0, i ? 2.4 : -0.8, 8.0);
    const shape::MeshDistance md(s.car.body.mesh);
    const Eigen::Vector3d size = s.car.body.size;
    const double bearing = i ? 2.4 : -0.8;
    const Eigen::Vector3d cam_obj(8 * std::cos(bearing), 8 * std::sin(bearing), 1.7 - size.z() / 2);
    shape::Random rng(40 + i);
    for (int r = 0; r < 12; ++r)
      for (int c = 0; c < 24; ++c) {
        // Aim at a grid over the box's silhouette from the camera.
        const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(-cam_obj).normalized();
        const Eigen::Vector3d target = side * (c - 11.5) / 11.5 * 2.6 + Eigen::Vector3d(0, 0, (r - 5.5) / 5.5 * 0.9);
        const Eigen::Vector3d u = (target - cam_obj).normalized();
        const double t = md.rayHit(cam_obj, u);
        if (!std::isfinite(t)) continue;
        fit::DepthRay ray;
        ray.origin_world = s.T_world_obj * cam_obj;
        ray.direction_world = s.T_world_obj.linear() * u;
        ray.depth_m = t + 0.02 * (rng.uniform() + rng.uniform() + rng.uniform() - 1.5) * 2;
        s.obs.rays.push_back(ray);
      }
    ASSERT_GT(s.obs.rays.size(), 80u);
    const fit::FitResult r = fitFromStart(s, size);
    ASSERT_TRUE(r.ok) << r.why;
    const Errors e = errors(s, r);
    expectErrorsBelow(e, {0.15, 5.0, 0.10}, i, s);
  }
}

TEST(Silhouette, LeastLevelMatchesADenseSearchAndItsGradientTheNumericOne) {
  const auto& prior = test::shippedPrior();
  const int K = prior.dimensions();
  ASSERT_LE(K, 8);
  shape::Random rng(3);
  int near_misses = 0, through = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const double bearing = rng.uniform(-M_PI, M_PI);
    const Eigen::Vector3d o(9 * std::cos(bearing), 9 * std::sin(bearing), rng.uniform(0.0, 1.2));
    // Aim across the car's outline: some rays pass it, some go through.
    const Eigen::Vector3d target(rng.uniform(-3.0, 3.0), rng.uniform(-1.4, 1.4), rng.uniform(-1.0, 1.0));
    const Eigen::Vector3d u = (target - o).normalized();
    const std::vector<double> z = randomCode(prior, rng);
    // An independent, precise least level over the searched stretch (within the box's bounding sphere grown
    // by kSearchMargin): a dense search (1 mm steps), then golden sections to 1e-10 m.
    const double radius =
        0.5 * Eigen::Vector3d(kCheckedCarSize[0], kCheckedCarSize[1], kCheckedCarSize[2]).norm() + fit::kSearchMargin;
    auto least = [&](const Eigen::Vector3d& oo, const Eigen::Vector3d& uu, const std::vector<double>& zz) {
      auto level = [&](double t) {
        const Eigen::Vector3d p = oo + t * uu;
        const double pv[3] = {p.x(), p.y(), p.z()};
        return prior.levelSized<double>(pv, kCheckedCarSize, zz.data());
      };
      double best = 1e9, tb = 0;
      for (double t = 0; t < 20; t += 0.001)
        if (const double l = level(t); l < best && (oo + t * uu).norm() <= radius) best = l, tb = t;
      double a = std::max(0.0, tb - 0.001), b = tb + 0.001;
      for (int i = 0; i < 80 && b - a > 1e-10; ++i) {
        const double c = b - 0.618 * (b - a), e = a + 0.618 * (b - a);
        (level(c) < level(e) ? b : a) = level(c) < level(e) ? e : c;
      }
      return std::min(best, level(0.5 * (a + b)));
    };
    const double dense = least(o, u, z);
    double t_found;
    const double ov[3] = {o.x(), o.y(), o.z()}, uv[3] = {u.x(), u.y(), u.z()};
    const double m = fit::leastLevel(prior, ov, uv, kCheckedCarSize, z.data(), &t_found);
    // The search's steps may pick the higher of two valleys close in value (silhouette.hpp).
    EXPECT_NEAR(m, dense, 1e-4 + 0.03 * std::abs(dense)) << "trial " << trial;
    if (std::abs(m - dense) > 1e-4) continue;  // another valley: its own derivative
    if (m <= 0.005) {                          // inside, the least level may sit on a kink between cells: values only
      ++through;
      continue;
    }
    ++near_misses;
    // The Jet's derivative against central differences of the least level (the envelope theorem).
    const RayJets in(o, u, z);
    const RayJet mj = fit::silhouetteLevel(prior, in.origin, in.direction, in.size, in.code);
    EXPECT_NEAR(mj.a, m, 1e-4);
    const double h = 1e-5;
    const double tol = 3e-2 * std::max(1.0, mj.v.cwiseAbs().maxCoeff());
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(a) * h;
      EXPECT_NEAR(mj.v[a], (least(o + e, u, z) - least(o - e, u, z)) / (2 * h), tol)
          << "trial " << trial << " origin " << a;
      EXPECT_NEAR(mj.v[3 + a], (least(o, u + e, z) - least(o, u - e, z)) / (2 * h), tol)
          << "trial " << trial << " direction " << a;
    }
    for (int k = 0; k < K; ++k) {
      std::vector<double> zp = z, zm = z;
      zp[k] += h, zm[k] -= h;
      EXPECT_NEAR(mj.v[6 + k], (least(o, u, zp) - least(o, u, zm)) / (2 * h), tol)
          << "trial " << trial << " code " << k;
    }
  }
  EXPECT_GE(near_misses, 10);
  EXPECT_GE(through, 10);
}

namespace {

// Rays of one view of the car (camera at `range` metres and `bearing` in the object frame, 1.7 m above the
// road): a 24 x 12 grid over the car's outline grown by a third, rays that hit the true mesh are its mask,
// the rest background. Returns how many are inside.
int addSilhouetteView(Scenario& s, const shape::MeshDistance& md, double bearing, double range) {
  const Eigen::Vector3d size = s.car.body.size;
  const Eigen::Vector3d cam_obj(range * std::cos(bearing), range * std::sin(bearing), 1.7 - size.z() / 2);
  const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(-cam_obj).normalized();
  int inside = 0;
  for (int r = 0; r < 12; ++r)
    for (int c = 0; c < 24; ++c) {
      const Eigen::Vector3d target = side * (c - 11.5) / 11.5 * 3.2 + Eigen::Vector3d(0, 0, (r - 5.5) / 5.5 * 1.1);
      const Eigen::Vector3d u = (target - cam_obj).normalized();
      fit::SilhouetteRay ray;
      ray.origin_world = s.T_world_obj * cam_obj;
      ray.direction_world = s.T_world_obj.linear() * u;
      ray.inside = std::isfinite(md.rayHit(cam_obj, u));
      inside += ray.inside;
      s.obs.silhouette.push_back(ray);
    }
  return inside;
}

}  // namespace

TEST(ObjectFit, RecoversACarFromItsSilhouettesInSeveralViews) {
  // Four views from a camera driving past (bearings 40 degrees apart, 8 m). No points, no depths, no box
  // prior: the silhouettes alone, from the usual 0.5 m, 10 degree start.
  for (int i = 0; i < 2; ++i) {
    Scenario s = scenario(10 + i, 0, 0.0, 0.0, 8.0);
    const shape::MeshDistance md(s.car.body.mesh);
    const Eigen::Vector3d size = s.car.body.size;
    int inside = 0;
    for (int view = 0; view < 4; ++view)
      inside += addSilhouetteView(s, md, (i ? 2.0 : -1.2) + view * 40.0 * M_PI / 180, 8.0);
    ASSERT_GT(inside, 300);
    const fit::FitResult r = fitFromStart(s, size);
    ASSERT_TRUE(r.ok) << r.why;
    const Errors e = errors(s, r);
    std::printf("silhouette car %d: centre %.3f m, yaw %.2f deg, chamfer %.3f m\n", i, e.centre, e.yaw_deg, e.chamfer);
    expectErrorsBelow(e, {0.15, 5.0, 0.10}, i, s);
  }
}

TEST(ObjectFit, PlacesACarFromOneViewsSilhouetteAndItsBox) {
  // A car seen in one keyframe (the reconstructor's min_silhouette_keyframes 1): its outline in one view
  // and the metric box's consensus as the prior (the plugin's box_sigma 0.5 m, 20 degrees). The box is
  // 0.5 m and 10 degrees off, as in every fit test; one view fixes the car across the ray and, through
  // the prior's metric size, along it: each fit ends nearer than its box, and the median car within 0.25 m
  // (measured 0.08-0.31 m, 1.4-7.6 degrees; four views, the test above, do better).
  const double bearings[] = {-1.2, 2.0, 0.9, -2.4};
  std::vector<double> centres;
  for (int i = 0; i < 4; ++i) {
    Scenario s = scenario(10 + i, 0, 0.0, 0.0, 8.0);
    const shape::MeshDistance md(s.car.body.mesh);
    ASSERT_GT(addSilhouetteView(s, md, bearings[i], 10.0), 60);
    s.obs.T_world_obj_boxes = s.T_init;
    const fit::FitResult r = fitFromStart(s, s.car.body.size);
    ASSERT_TRUE(r.ok) << r.why;
    const Errors e = errors(s, r);
    std::printf("one-view car %d: centre %.3f m, yaw %.2f deg, chamfer %.3f m (box 0.5 m, 10 deg)\n", i, e.centre,
                e.yaw_deg, e.chamfer);
    expectErrorsBelow(e, {0.4, 9.0, 0.15}, i, s);
    centres.push_back(e.centre);
  }
  std::sort(centres.begin(), centres.end());
  EXPECT_LT((centres[1] + centres[2]) / 2, 0.25);
}
