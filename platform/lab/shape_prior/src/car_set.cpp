#include "beslam/shape_prior/car_set.hpp"

#include <algorithm>
#include <cmath>

#include "beslam/sim/car_mesh.hpp"

namespace beslam::recon::tools {
namespace {

constexpr double kTyreWidth = 0.008;  // the tyres stand 4 mm proud of each side

Car makeCar(sim::CarShapeClass cls, double l, double w, double h, const sim::CarProfile* profile) {
  const sim::CarMesh m = sim::carMesh(cls, l, w, h, profile);
  Car car;
  car.shape = sim::carShapeName(cls);
  car.body.size = Eigen::Vector3d(l, w + kTyreWidth, h);
  for (const auto& v : m.vertices) car.body.mesh.vertices.push_back(v - Eigen::Vector3d(0, 0, h / 2));
  car.body.mesh.faces = m.faces;
  shape::orientOutward(car.body.mesh);  // the generator's faces follow the renderer, not one orientation
  return car;
}

}  // namespace

std::vector<Car> trainingCars(int n, std::uint64_t seed) {
  shape::Random rng(seed);
  std::vector<Car> out;
  for (int i = 0; i < n; ++i) {
    const auto cls = static_cast<sim::CarShapeClass>(std::min(4, static_cast<int>(rng.uniform() * 5)));
    const sim::CarSizeRange r = sim::sequenceSizeRange(cls);
    auto widened = [&](double lo, double hi) {
      const double pad = 0.06 * (lo + hi) / 2;
      return rng.uniform(lo - pad, hi + pad);
    };
    const double l = widened(r.l_min, r.l_max), w = widened(r.w_min, r.w_max), h = widened(r.h_min, r.h_max);
    sim::CarProfile p = sim::defaultCarProfile(cls);
    p.hb += rng.uniform(-0.03, 0.03);
    p.x_wb = std::min(0.5, p.x_wb + rng.uniform(-0.03, 0.03));
    p.x_rf = std::min(p.x_wb - 0.02, p.x_rf + rng.uniform(-0.03, 0.03));
    p.x_rr = std::clamp(p.x_rr + rng.uniform(-0.03, 0.03), -0.48, p.x_rf - 0.05);
    p.x_rb = std::clamp(p.x_rb + rng.uniform(-0.02, 0.02), -0.5, p.x_rr - 0.01);
    out.push_back(makeCar(cls, l, w, h, &p));
  }
  return out;
}

std::vector<Car> heldOutCars(int n, std::uint64_t seed) {
  shape::Random rng(seed ^ 0x6865'6c64'6f75'7421ull);  // "heldout!"
  std::vector<Car> out;
  for (int i = 0; i < n; ++i) {
    const double u = rng.uniform();
    const auto cls = u < 0.30   ? sim::CarShapeClass::Sedan
                     : u < 0.52 ? sim::CarShapeClass::Hatchback
                     : u < 0.70 ? sim::CarShapeClass::Wagon
                     : u < 0.87 ? sim::CarShapeClass::Suv
                                : sim::CarShapeClass::Van;
    const sim::CarSizeRange r = sim::sequenceSizeRange(cls);
    const double l = rng.uniform(r.l_min, r.l_max), w = rng.uniform(r.w_min, r.w_max),
                 h = rng.uniform(r.h_min, r.h_max);
    out.push_back(makeCar(cls, l, w, h, nullptr));
  }
  return out;
}

std::vector<shape::TrainingShape> bodies(const std::vector<Car>& cars) {
  std::vector<shape::TrainingShape> out;
  for (const auto& c : cars) out.push_back(c.body);
  return out;
}

}  // namespace beslam::recon::tools

namespace beslam::recon::tools {

std::vector<Eigen::Vector3d> visibleSurfacePoints(const shape::Mesh& mesh, const Eigen::Vector3d& sensor_obj, int n,
                                                  double noise_m, std::uint64_t seed) {
  const shape::MeshDistance md(mesh);
  const auto candidates = shape::surfaceSamples(mesh, 6 * n, seed, true);
  shape::Random rng(seed + 17);
  auto gauss = [&] {  // Box-Muller
    const double u1 = std::max(1e-300, rng.uniform()), u2 = rng.uniform();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  };
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : candidates) {
    if (static_cast<int>(out.size()) >= n) break;
    if (md.segmentHits(sensor_obj, p, 0.005)) continue;
    out.push_back(p + noise_m * Eigen::Vector3d(gauss(), gauss(), gauss()));
  }
  return out;
}

}  // namespace beslam::recon::tools

namespace beslam::recon::tools {

std::vector<ObjectRay> depthPatch(const shape::Mesh& mesh, const Eigen::Vector3d& camera_obj,
                                  const Eigen::Vector3d& size, int cols, int rows, double noise_m, std::uint64_t seed) {
  const shape::MeshDistance md(mesh);
  const Eigen::Vector3d side = Eigen::Vector3d::UnitZ().cross(-camera_obj).normalized();
  const double half_width = 0.5 * std::hypot(size.x(), size.y()) + 0.3, half_height = 0.5 * size.z() + 0.15;
  shape::Random rng(seed);
  std::vector<ObjectRay> out;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const double fc = cols > 1 ? 2.0 * c / (cols - 1) - 1 : 0, fr = rows > 1 ? 2.0 * r / (rows - 1) - 1 : 0;
      const Eigen::Vector3d target = side * fc * half_width + Eigen::Vector3d(0, 0, fr * half_height);
      const Eigen::Vector3d u = (target - camera_obj).normalized();
      const double t = md.rayHit(camera_obj, u);
      if (!std::isfinite(t)) continue;
      const double noise = 2 * (rng.uniform() + rng.uniform() + rng.uniform() - 1.5);  // std 1
      out.push_back({u, t + noise_m * noise});
    }
  return out;
}

}  // namespace beslam::recon::tools
