// Shape prior on its own (no simulator): training determinism, the file and its failures, the signed
// distance (sign, metric slope, autodiff gradient), meshes and PLY.
#include "shape/shape_prior.hpp"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "beslam/formats/error.hpp"
#include "beslam/test/error_text.hpp"

namespace fs = std::filesystem;
using namespace beslam::recon::shape;

namespace {

void addBox(Mesh& m, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const int b = static_cast<int>(m.vertices.size());
  for (int c = 0; c < 8; ++c)
    m.vertices.emplace_back(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(), c & 4 ? hi.z() : lo.z());
  // Counter-clockwise seen from outside (corner bits x = 1, y = 2, z = 4).
  const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : f) m.faces.push_back({b + t[0], b + t[1], b + t[2]});
}

// A toy "car": a lower box over the whole footprint and a narrower cabin box standing on it, in a box of
// `size` (object frame, centre origin). body_top and cabin_len vary between shapes.
TrainingShape toyCar(const Eigen::Vector3d& size, double body_top, double cabin_len) {
  TrainingShape s;
  s.size = size;
  const Eigen::Vector3d h = size / 2;
  addBox(s.mesh, -h, Eigen::Vector3d(h.x(), h.y(), -h.z() + body_top * size.z()));
  addBox(s.mesh, Eigen::Vector3d(-cabin_len / 2 * size.x(), -0.8 * h.y(), -h.z() + body_top * size.z()),
         Eigen::Vector3d(cabin_len / 2 * size.x() * 0.6, 0.8 * h.y(), h.z()));
  return s;
}

std::vector<TrainingShape> toyCars(int n) {
  std::vector<TrainingShape> out;
  Random rng(5);
  for (int i = 0; i < n; ++i)
    out.push_back(toyCar(Eigen::Vector3d(rng.uniform(3.8, 5), rng.uniform(1.6, 2), rng.uniform(1.3, 1.9)),
                         rng.uniform(0.45, 0.65), rng.uniform(0.4, 0.7)));
  return out;
}

TrainOptions tinyOptions() {
  TrainOptions o;
  o.grid = {20, 12, 12};
  o.dims = 3;
  o.seed = 9;
  return o;
}

const ShapePrior& toyPrior() {
  static const ShapePrior prior = trainShapePrior(toyCars(12), tinyOptions());
  return prior;
}

std::string tempPath(const std::string& name) {
  return (fs::temp_directory_path() / ("beslam_shape_" + name)).string();
}

// The error load() throws for a file, or "" when it loads.
std::string loadError(const std::string& path) {
  return beslam::test::errorText<beslam::Error>([&] { ShapePrior::load(path); });
}

}  // namespace

TEST(ShapePrior, TrainingIsDeterministicAndTheFileRoundTrips) {
  const ShapePrior a = trainShapePrior(toyCars(12), tinyOptions());
  const ShapePrior b = trainShapePrior(toyCars(12), tinyOptions());
  EXPECT_EQ(a.serialise(), b.serialise());
  EXPECT_EQ(a.dimensions(), 3);
  EXPECT_EQ(a.trainingShapes(), 12);
  const std::string path = tempPath("roundtrip.bsdf");
  a.save(path);
  const ShapePrior c = ShapePrior::load(path);
  EXPECT_EQ(c.serialise(), a.serialise());
  EXPECT_EQ(c.seed(), 9u);
  const Eigen::Vector3d size(4.5, 1.8, 1.5);
  Eigen::VectorXd z(3);
  z << 0.3, -0.2, 0.1;
  z = z.cwiseProduct(a.codeStd());
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.3, 0.2, 0.1), Eigen::Vector3d(3, -1, 2)})
    EXPECT_EQ(a.distance(p, size, z), c.distance(p, size, z));
  fs::remove(path);
}

TEST(ShapePrior, BadFilesGiveOneErrorNamingTheFile) {
  const std::string good = toyPrior().serialise();
  const std::string path = tempPath("bad.bsdf");
  auto write = [&](const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; };

  std::string damaged = good;
  damaged[damaged.size() / 2] ^= 0x55;
  write(damaged);
  std::string e = loadError(path);
  EXPECT_EQ(e.rfind(path + ": ", 0), 0u) << e;
  EXPECT_NE(e.find("checksum"), std::string::npos) << e;

  write(good.substr(0, good.size() - 100));
  e = loadError(path);
  EXPECT_EQ(e.rfind(path + ": ", 0), 0u) << e;
  EXPECT_NE(e.find("truncated"), std::string::npos) << e;

  write(good.substr(0, 20));
  EXPECT_NE(loadError(path).find("truncated"), std::string::npos) << loadError(path);

  std::string version = good;
  version[8] = 7;  // the version follows the 8-byte magic
  write(version);
  e = loadError(path);
  EXPECT_EQ(e.rfind(path + ": ", 0), 0u) << e;
  EXPECT_NE(e.find("version 7"), std::string::npos) << e;

  write("ply\nnot a prior at all");
  EXPECT_NE(loadError(path).find("not a BE-SLAM shape prior"), std::string::npos);

  fs::remove(path);
  EXPECT_EQ(loadError(path).rfind(path, 0), 0u);  // missing file
}

TEST(ShapePrior, SignedDistanceHasTheRightSignAndMetricSlope) {
  const ShapePrior& prior = toyPrior();
  const Eigen::Vector3d size(4.4, 1.8, 1.6);
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(prior.dimensions());
  EXPECT_LT(prior.distance(Eigen::Vector3d(0, 0, -0.3), size, z), -0.2);  // inside the lower body
  EXPECT_GT(prior.distance(Eigen::Vector3d(3.0, 0, 0), size, z), 0.5);    // in front
  EXPECT_GT(prior.distance(Eigen::Vector3d(0, 1.5, 0), size, z), 0.4);    // beside
  EXPECT_GT(prior.distance(Eigen::Vector3d(0, 0, 10.0), size, z), 8.0);   // far above, outside the grid
  // Near the flat faces the distance is metric: slope 1 along the face normal, whatever the axis scale.
  const Eigen::Vector3d faces[] = {{2.2, 0, -0.5}, {-2.2, 0, -0.5}, {0.5, 0.9, -0.5}, {0.5, 0, -0.8}};
  const Eigen::Vector3d normals[] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, 0, -1}};
  for (int i = 0; i < 4; ++i) {
    const double d0 = prior.distance(faces[i] + 0.05 * normals[i], size, z);
    const double d1 = prior.distance(faces[i] + 0.15 * normals[i], size, z);
    EXPECT_NEAR((d1 - d0) / 0.1, 1.0, 0.1) << "face " << i;
    EXPECT_NEAR(d0, 0.05, 0.04) << "face " << i;
  }
  // Never NaN, also far outside and for a NaN point.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(std::isnan(prior.distance(Eigen::Vector3d(1e6, -1e6, 1e6), size, z)));
  EXPECT_FALSE(std::isnan(prior.distance(Eigen::Vector3d(nan, 0, 0), size, z)));
}

TEST(ShapePrior, AutodiffGradientMatchesNumeric) {
  const ShapePrior& prior = toyPrior();
  const int K = prior.dimensions();
  using J = ceres::Jet<double, 6>;
  const Eigen::Vector3d size(4.6, 1.8, 1.5);
  Random rng(3);
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Vector3d p(rng.uniform(-3, 3), rng.uniform(-1.4, 1.4), rng.uniform(-1.2, 1.2));
    Eigen::VectorXd z(K);
    for (int k = 0; k < K; ++k) z(k) = rng.uniform(-1, 1) * prior.codeStd()(k);
    J pj[3], zj[3];
    for (int a = 0; a < 3; ++a) pj[a] = J(p(a), a);
    for (int k = 0; k < K; ++k) zj[k] = J(z(k), 3 + k);
    const J d = prior.distance(pj, size, zj);
    EXPECT_NEAR(d.a, prior.distance(p, size, z), 1e-12);
    const double h = 1e-6;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(a) * h;
      const double num = (prior.distance(p + e, size, z) - prior.distance(p - e, size, z)) / (2 * h);
      EXPECT_NEAR(d.v[a], num, 1e-4 * std::max(1.0, std::abs(num))) << "trial " << trial << " axis " << a;
    }
    for (int k = 0; k < K; ++k) {
      Eigen::VectorXd zp = z, zm = z;
      zp(k) += h, zm(k) -= h;
      const double num = (prior.distance(p, size, zp) - prior.distance(p, size, zm)) / (2 * h);
      EXPECT_NEAR(d.v[3 + k], num, 1e-4 * std::max(1.0, std::abs(num))) << "trial " << trial << " code " << k;
    }
  }
}

TEST(ShapePrior, MeshIsClosedOutwardInsideTheBoxAndRoundTripsAsPly) {
  const ShapePrior& prior = toyPrior();
  const Eigen::Vector3d size(4.5, 1.8, 1.5);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(prior.dimensions());
  z(0) = prior.codeStd()(0);
  const Mesh m = prior.mesh(z, size);
  ASSERT_GT(m.faces.size(), 100u);
  // Closed: every edge is shared by exactly two faces, once in each direction.
  std::map<std::pair<int, int>, int> directed;
  for (const auto& f : m.faces)
    for (int e = 0; e < 3; ++e) ++directed[{f[e], f[(e + 1) % 3]}];
  int open = 0;
  for (const auto& [edge, count] : directed)
    if (count != 1 || !directed.count({edge.second, edge.first})) ++open;
  EXPECT_EQ(open, 0);
  double volume = 0;  // positive for outward faces
  for (const auto& f : m.faces) volume += m.vertices[f[0]].dot(m.vertices[f[1]].cross(m.vertices[f[2]])) / 6;
  EXPECT_GT(volume, 0.5 * size.prod());
  EXPECT_LT(volume, 1.1 * size.prod());
  for (const auto& v : m.vertices) EXPECT_TRUE((v.cwiseAbs() - size / 2).maxCoeff() < 0.1) << v.transpose();
  // The mesh is piecewise linear per tetrahedron, the distance trilinear per cell: on this coarse grid
  // (cells 0.18-0.31 m) they part by up to about a sixth of a cell.
  for (const auto& p : prior.surfaceSamples(z, size, 50)) EXPECT_NEAR(prior.distance(p, size, z), 0.0, 0.05);

  const std::string path = tempPath("mesh.ply");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(10, -2, 0.75);
  beslam::formats::writePlyMesh(path, m, T);
  const Mesh back = beslam::formats::readPlyMesh(path);
  EXPECT_EQ(back.vertices.size(), m.vertices.size());
  EXPECT_EQ(back.faces.size(), m.faces.size());
  EXPECT_NEAR((back.vertices[0] - T * m.vertices[0]).norm(), 0.0, 1e-5);
  EXPECT_EQ(back.faces.back(), m.faces.back());
  fs::remove(path);
}

TEST(MeshDistance, WindingNumberSurvivesOverlapsAndHoles) {
  Mesh m;
  addBox(m, Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 0));
  addBox(m, Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(0.5, 0.5, 1));  // overlaps the first
  m.faces.erase(m.faces.begin() + 12);  // a hole: one bottom triangle of the second box (inside the first)
  const MeshDistance d(m);
  EXPECT_LT(d.signedDistance(Eigen::Vector3d(0, 0, -0.2)), 0);  // in both
  EXPECT_LT(d.signedDistance(Eigen::Vector3d(0, 0, 0.5)), 0);   // in the upper box only
  EXPECT_GT(d.signedDistance(Eigen::Vector3d(0.8, 0.8, 0.5)), 0);
  EXPECT_NEAR(d.signedDistance(Eigen::Vector3d(0, 0, 1.3)), 0.3, 1e-12);
  EXPECT_NEAR(d.signedDistance(Eigen::Vector3d(0.9, 0, -0.5)), -0.1, 1e-12);
}
