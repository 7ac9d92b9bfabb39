#include "synthetic_scan.hpp"

#include <cmath>
#include <limits>
#include <random>

namespace beslam::detector_lidar::synth {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Ray (origin o, unit direction d) against an oriented box; returns the entry distance or +inf.
double hitBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Object& b, double ground_z) {
  const double c = std::cos(-b.yaw), s = std::sin(-b.yaw);
  const Eigen::Vector3d po(c * (o.x() - b.center_xy.x()) - s * (o.y() - b.center_xy.y()),
                           s * (o.x() - b.center_xy.x()) + c * (o.y() - b.center_xy.y()),
                           o.z() - (ground_z + b.bottom + b.height / 2));
  const Eigen::Vector3d pd(c * d.x() - s * d.y(), s * d.x() + c * d.y(), d.z());
  const Eigen::Vector3d half(b.length / 2, b.width / 2, b.height / 2);
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(pd[k]) < 1e-12) {
      if (std::abs(po[k]) > half[k]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double a = (-half[k] - po[k]) / pd[k], e = (half[k] - po[k]) / pd[k];
    if (a > e) std::swap(a, e);
    t0 = std::max(t0, a), t1 = std::min(t1, e);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0 > 0 ? t0 : std::numeric_limits<double>::infinity();
}
}  // namespace

Eigen::Isometry3d kittiLikeTcamLidar() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 0, -1, 0,  //
      0, 0, -1,            //
      1, 0, 0;
  T.translation() = Eigen::Vector3d(0.0, -0.08, -0.27);
  return T;
}

beslam_camera kittiLikeCamera() { return {sizeof(beslam_camera), 1242, 375, 0, 721.5, 721.5, 609.6, 172.9}; }

Scene randomScene(uint32_t seed, int cars, double max_distance) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0, 1);
  auto uni = [&](double a, double b) { return a + (b - a) * u01(rng); };
  Scene scene;
  auto free = [&](const Eigen::Vector2d& c, double r) {
    for (const Object& o : scene.objects)
      if ((o.center_xy - c).norm() < r + std::max(o.length, o.width) / 2 + 0.4) return false;
    return true;
  };
  for (int attempt = 0; attempt < 2000 && static_cast<int>(scene.objects.size()) < cars; ++attempt) {
    Object car;
    const double range = uni(4.5, max_distance), bearing = uni(-36, 36) * kDeg;
    car.center_xy = Eigen::Vector2d(range * std::cos(bearing), range * std::sin(bearing));
    if (std::abs(car.center_xy.y()) > 14) continue;  // on the street, clear of the building front at y = -16
    car.length = uni(3.6, 4.8), car.width = uni(1.55, 1.9), car.height = uni(1.35, 1.75);
    car.yaw = u01(rng) < 0.7 ? uni(-0.15, 0.15) + (u01(rng) < 0.5 ? 0 : kPi) : uni(-kPi, kPi);
    if (free(car.center_xy, car.length / 2)) scene.objects.push_back(car);
  }
  for (int i = 0; i < 4; ++i) {  // poles and pedestrians
    Object o;
    o.is_car = false;
    const bool pole = i % 2 == 0;
    o.length = pole ? 0.25 : 0.6, o.width = pole ? 0.25 : 0.5, o.height = pole ? 4.0 : 1.75;
    const double range = uni(5, max_distance), bearing = uni(-38, 38) * kDeg;
    o.center_xy = Eigen::Vector2d(range * std::cos(bearing), range * std::sin(bearing));
    if (free(o.center_xy, 0.5)) scene.objects.push_back(o);
  }
  Object wall;  // a building front along the street, beyond the cars
  wall.is_car = false;
  wall.center_xy = Eigen::Vector2d(30, -16);
  wall.length = 60, wall.width = 0.5, wall.height = 6;
  scene.objects.push_back(wall);
  return scene;
}

Scan castScan(const Scene& scene, uint32_t seed, double az_step_deg, double fov_deg) {
  std::mt19937 rng(seed * 7919u + 1);
  std::normal_distribution<double> noise(0, scene.noise);
  Scan scan;
  scan.hits_per_object.assign(scene.objects.size(), 0);
  const Eigen::Vector3d origin(0, 0, 0);
  const double ground_z = -scene.lidar_height;
  for (int beam = 0; beam < 64; ++beam) {
    const double elevation = (2.0 - beam * (26.8 / 63.0)) * kDeg;
    for (double az = -fov_deg; az <= fov_deg; az += az_step_deg) {
      const Eigen::Vector3d d(std::cos(elevation) * std::cos(az * kDeg), std::cos(elevation) * std::sin(az * kDeg),
                              std::sin(elevation));
      double best = d.z() < 0 ? ground_z / d.z() : std::numeric_limits<double>::infinity();
      int hit = -1;
      for (size_t k = 0; k < scene.objects.size(); ++k) {
        const double t = hitBox(origin, d, scene.objects[k], ground_z);
        if (t < best) best = t, hit = static_cast<int>(k);
      }
      if (!(best < 80.0)) continue;
      const double r = best + noise(rng);
      const Eigen::Vector3d p = r * d;
      scan.xyzi.insert(scan.xyzi.end(), {static_cast<float>(p.x()), static_cast<float>(p.y()),
                                         static_cast<float>(p.z()), hit >= 0 ? 0.5f : 0.2f});
      if (hit >= 0) ++scan.hits_per_object[static_cast<size_t>(hit)];
    }
  }
  return scan;
}

std::vector<beslam_box3d> truthBoxes(const Scene& scene, const Eigen::Isometry3d& T_cam_lidar) {
  std::vector<beslam_box3d> boxes;
  for (const Object& o : scene.objects) {
    if (!o.is_car) continue;
    const Eigen::Vector3d c_lidar(o.center_xy.x(), o.center_xy.y(), -scene.lidar_height + o.bottom + o.height / 2);
    const Eigen::Vector3d c_cam = T_cam_lidar * c_lidar;
    const Eigen::Vector3d heading = T_cam_lidar.linear() * Eigen::Vector3d(std::cos(o.yaw), std::sin(o.yaw), 0);
    beslam_box3d b{};
    b.class_id = BESLAM_CLASS_CAR;
    b.track_id = -1;
    for (int k = 0; k < 3; ++k) b.center_cam[k] = c_cam[k];
    b.size[0] = o.length, b.size[1] = o.width, b.size[2] = o.height;
    b.yaw = std::atan2(-heading.z(), heading.x());
    b.score = 1;
    boxes.push_back(b);
  }
  return boxes;
}

}  // namespace beslam::detector_lidar::synth
