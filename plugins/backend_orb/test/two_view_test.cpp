// Two-view initialisation on simulated geometry: a 3D scene picks F and recovers the motion, a plane
// picks H; both triangulate most inliers in front of the cameras.
#include "init/two_view.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

namespace beslam::orb {
namespace {

const Camera kCam{1226, 370, 718.856, 718.856, 607.19, 185.22};

struct Scene {
  std::vector<cv::KeyPoint> k1, k2;
  std::vector<int> matches;
  Eigen::Matrix3d R21;
  Eigen::Vector3d t21;
};

Scene makeScene(bool planar, uint64_t seed, int outliers = 0) {
  std::mt19937 rng(static_cast<unsigned>(seed));
  std::uniform_real_distribution<double> ux(-8, 8), uy(-2, 2), uz(6, 30), noise(-0.5, 0.5);
  Scene s;
  s.R21 = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();
  s.t21 = Eigen::Vector3d(0.1, 0.0, -1.0);  // camera 2 one unit forward: t21 = -R21 * C2
  s.t21 = -s.R21 * Eigen::Vector3d(0.1, 0.02, 1.0);
  auto proj = [&](const Eigen::Vector3d& p) {
    return cv::Point2f(static_cast<float>(kCam.fx * p.x() / p.z() + kCam.cx),
                       static_cast<float>(kCam.fy * p.y() / p.z() + kCam.cy));
  };
  while (static_cast<int>(s.k1.size()) < 400) {
    Eigen::Vector3d X(ux(rng), uy(rng), uz(rng));
    if (planar) X.z() = 12.0 + 0.3 * X.x() + 0.5 * X.y();  // a tilted wall ahead
    const Eigen::Vector3d X2 = s.R21 * X + s.t21;
    if (X2.z() < 1) continue;
    cv::Point2f p1 = proj(X), p2 = proj(X2);
    if (p1.x < 0 || p1.y < 0 || p1.x >= kCam.width || p1.y >= kCam.height) continue;
    if (p2.x < 0 || p2.y < 0 || p2.x >= kCam.width || p2.y >= kCam.height) continue;
    p1 += cv::Point2f(static_cast<float>(noise(rng)), static_cast<float>(noise(rng)));
    p2 += cv::Point2f(static_cast<float>(noise(rng)), static_cast<float>(noise(rng)));
    s.k1.emplace_back(p1, 7.f);
    s.k2.emplace_back(p2, 7.f);
  }
  s.matches.resize(s.k1.size());
  for (size_t i = 0; i < s.k1.size(); ++i) s.matches[i] = static_cast<int>(i);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(s.k1.size()) - 1);
  for (int o = 0; o < outliers; ++o) std::swap(s.matches[pick(rng)], s.matches[pick(rng)]);
  return s;
}

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
}

TEST(TwoView, GeneralSceneRecoversMotionWithTheFundamentalMatrix) {
  const Scene s = makeScene(false, 1, 20);
  TwoViewInitializer init(kCam, TwoViewOptions{});
  TwoViewResult r;
  ASSERT_TRUE(init.reconstruct(s.k1, s.k2, s.matches, r));
  EXPECT_FALSE(r.used_homography);
  EXPECT_LT(Eigen::AngleAxisd(r.R21 * s.R21.transpose()).angle(), 0.01);
  EXPECT_LT(angleBetween(r.t21, s.t21), 0.05);
  EXPECT_GT(r.n_triangulated, 250);
  for (size_t i = 0; i < r.points.size(); ++i) {
    if (r.triangulated[i]) {
      EXPECT_GT(r.points[i].z(), 0);
    }
  }
}

TEST(TwoView, PlanarSceneChoosesTheHomography) {
  const Scene s = makeScene(true, 2);
  TwoViewInitializer init(kCam, TwoViewOptions{});
  TwoViewResult r;
  const bool ok = init.reconstruct(s.k1, s.k2, s.matches, r);
  EXPECT_TRUE(r.used_homography);
  EXPECT_GT(r.score_h / (r.score_h + r.score_f), 0.40);
  // A plane seen from two views has two motions that put every point in front of both cameras; with
  // no clear winner the initializer waits for another frame, and it must never return the wrong one.
  if (ok) {
    EXPECT_LT(Eigen::AngleAxisd(r.R21 * s.R21.transpose()).angle(), 0.02);
    EXPECT_LT(angleBetween(r.t21, s.t21), 0.1);
  }
}

TEST(TwoView, PureRotationIsRejected) {
  Scene s = makeScene(false, 3);
  // Same pixels moved by a rotation only: no parallax, nothing to triangulate reliably.
  const Eigen::Matrix3d K = (Eigen::Matrix3d() << kCam.fx, 0, kCam.cx, 0, kCam.fy, kCam.cy, 0, 0, 1).finished();
  const Eigen::Matrix3d H = K * Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY()).toRotationMatrix() * K.inverse();
  for (size_t i = 0; i < s.k1.size(); ++i) {
    const Eigen::Vector3d p = H * Eigen::Vector3d(s.k1[i].pt.x, s.k1[i].pt.y, 1);
    s.k2[i].pt = cv::Point2f(static_cast<float>(p.x() / p.z()), static_cast<float>(p.y() / p.z()));
  }
  TwoViewInitializer init(kCam, TwoViewOptions{});
  TwoViewResult r;
  EXPECT_FALSE(init.reconstruct(s.k1, s.k2, s.matches, r));
}

TEST(TwoView, SameSeedSameResult) {
  const Scene s = makeScene(false, 4, 40);
  TwoViewResult a, b;
  TwoViewInitializer ia(kCam, TwoViewOptions{}), ib(kCam, TwoViewOptions{});
  ASSERT_TRUE(ia.reconstruct(s.k1, s.k2, s.matches, a));
  ASSERT_TRUE(ib.reconstruct(s.k1, s.k2, s.matches, b));
  EXPECT_EQ(a.R21, b.R21);
  EXPECT_EQ(a.t21, b.t21);
  EXPECT_EQ(a.n_triangulated, b.n_triangulated);
}

}  // namespace
}  // namespace beslam::orb
