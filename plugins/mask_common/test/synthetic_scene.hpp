// A small synthetic street scene for the mask tests and benchmark (no dependency on `beslam synth`):
// cars built from boxes (body, narrower cabin, four wheels) inside their 3D label box, a textured road
// and facade background, exact ground-truth instance masks, and a simulated 64-beam LiDAR ray-cast
// against the same geometry. Deterministic for a given seed.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "beslam/mask_common/box_projection.hpp"
#include "beslam/sdk/detector.hpp"
#include "beslam/sdk/views.hpp"

namespace beslam::mask::fixture {

struct Part {
  Eigen::Vector3d lo, hi;  // in the car's box frame (x length, y down, z width; origin at the box centre)
  double shade;            // grey level
};

struct Car {
  beslam_box3d box{};
  std::vector<Part> parts;
};

// A car of size l w h (box frame), body colour `grey`.
inline Car makeCar(int id, double x, double z, double yaw, double l, double w, double h, double grey, int motion,
                   double ground_y = 1.65) {
  Car c;
  c.box = sdk::newBox();
  c.box.class_id = BESLAM_CLASS_CAR;
  c.box.track_id = id;
  c.box.motion_state = motion;
  c.box.center_cam[0] = x, c.box.center_cam[1] = ground_y - h / 2, c.box.center_cam[2] = z;
  c.box.size[0] = l, c.box.size[1] = w, c.box.size[2] = h;
  c.box.yaw = yaw;
  auto up = [h](double height) { return h / 2 - height; };  // height above ground -> box-frame y
  const double body_top = 0.62 * h, cabin_w = w / 2 - 0.1;
  c.parts.push_back({{-l / 2, up(body_top), -w / 2}, {l / 2, up(0.3), w / 2}, grey});
  // Cabin: dark glass, as on real cars (contrasts with road and facades alike).
  c.parts.push_back({{-l / 2 + 0.28 * l, up(h), -cabin_w}, {l / 2 - 0.3 * l, up(body_top), cabin_w}, 40.0});
  for (int sx = -1; sx <= 1; sx += 2)
    for (int sz = -1; sz <= 1; sz += 2) {
      const double cx = sx * (l / 2 - 0.75), cz = sz * (w / 2 - 0.14);
      c.parts.push_back({{cx - 0.32, up(0.64), cz - 0.13}, {cx + 0.32, up(0.0), cz + 0.13}, 25.0});
    }
  return c;
}

inline Eigen::Matrix<double, 3, 8> partCorners(const Car& car, const Part& p) {
  Eigen::Matrix<double, 3, 8> c;
  for (int i = 0; i < 8; ++i)
    c.col(i) =
        Eigen::Vector3d((i & 1) ? p.hi.x() : p.lo.x(), (i & 2) ? p.hi.y() : p.lo.y(), (i & 4) ? p.hi.z() : p.lo.z());
  return sdk::boxPose(car.box) * c;
}

struct Scene {
  Intrinsics K;
  Eigen::Isometry3d T_cam_lidar = Eigen::Isometry3d::Identity();
  std::vector<Car> cars;
  cv::Mat gray;              // CV_8UC1
  cv::Mat instance;          // CV_16UC1 track ids
  std::vector<float> lidar;  // x y z i, LiDAR frame
};

inline Intrinsics kittiIntrinsics() {
  Intrinsics K;
  K.fx = K.fy = 718.856, K.cx = 607.1928, K.cy = 185.2157, K.width = 1241, K.height = 376;
  return K;
}

// Renders the cars (painter's order by part depth; nearer cars drawn last) over a textured background.
inline void render(Scene& s, uint32_t seed) {
  const Intrinsics& K = s.K;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, 2.f);
  s.gray = cv::Mat(K.height, K.width, CV_8UC1);
  // Background: facades with windows above the horizon, textured road below.
  const int horizon = static_cast<int>(K.cy);
  cv::Mat bg(K.height, K.width, CV_32F);
  for (int y = 0; y < K.height; ++y)
    for (int x = 0; x < K.width; ++x) {
      float v;
      if (y < horizon) {
        const int bx = x / 90, wx = x % 90, wy = y % 40;
        v = 120.f + 25.f * static_cast<float>((bx * 37) % 5) / 4.f;
        if (wx > 20 && wx < 60 && wy > 10 && wy < 30) v -= 45.f;  // windows
      } else {
        v = 95.f + 6.f * std::sin(x * 0.05f + y * 0.31f);
        if (std::abs(x - K.cx - (y - horizon) * 1.8) < 3) v = 200.f;  // a lane marking
      }
      bg.at<float>(y, x) = v;
    }
  // Cars far to near; each part's faces shaded so their boundaries make edges.
  s.instance = cv::Mat::zeros(K.height, K.width, CV_16UC1);
  std::vector<size_t> order(s.cars.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return Eigen::Vector3d(s.cars[a].box.center_cam).norm() > Eigen::Vector3d(s.cars[b].box.center_cam).norm();
  });
  for (size_t ci : order) {
    const Car& car = s.cars[ci];
    std::vector<std::pair<double, size_t>> parts;
    for (size_t k = 0; k < car.parts.size(); ++k) {
      const Eigen::Matrix<double, 3, 8> c = partCorners(car, car.parts[k]);
      parts.push_back({c.row(2).mean(), k});
    }
    std::sort(parts.rbegin(), parts.rend());
    for (const auto& [d, k] : parts) {
      const Eigen::Matrix<double, 3, 8> c = partCorners(car, car.parts[k]);
      if (c.row(2).minCoeff() < 0.3) continue;
      std::vector<cv::Point2f> pts;
      for (int i = 0; i < 8; ++i) {
        const Eigen::Vector2d uv = K.project(c.col(i));
        pts.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()));
      }
      std::vector<cv::Point2f> hull;
      cv::convexHull(pts, hull);
      std::vector<cv::Point> ih;
      for (const auto& p : hull) ih.emplace_back(cvRound(p.x * 16), cvRound(p.y * 16));
      cv::fillConvexPoly(bg, ih, cv::Scalar(car.parts[k].shade), cv::LINE_8, 4);
      cv::fillConvexPoly(s.instance, ih, cv::Scalar(car.box.track_id), cv::LINE_8, 4);
      // Faces of the body: a slightly different shade on the top face for an inner edge.
      if (k == 0) {
        std::vector<cv::Point> top;
        for (int i : {0, 1, 5, 4}) {
          const Eigen::Vector2d uv = K.project(c.col(i));
          top.emplace_back(cvRound(uv.x() * 16), cvRound(uv.y() * 16));
        }
        cv::fillConvexPoly(bg, top, cv::Scalar(car.parts[k].shade * 1.15), cv::LINE_8, 4);
      }
    }
  }
  cv::GaussianBlur(bg, bg, cv::Size(0, 0), 0.6);
  for (int y = 0; y < K.height; ++y)
    for (int x = 0; x < K.width; ++x)
      s.gray.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(bg.at<float>(y, x) + noise(rng));
}

// Slab test of a ray against an oriented part; returns the entry distance or -1.
inline double rayPart(const Car& car, const Part& p, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Isometry3d T = sdk::boxPose(car.box).inverse();
  const Eigen::Vector3d ol = T * o, dl = T.linear() * d;
  double t0 = 0, t1 = 1e9;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dl[a]) < 1e-12) {
      if (ol[a] < p.lo[a] || ol[a] > p.hi[a]) return -1;
      continue;
    }
    double ta = (p.lo[a] - ol[a]) / dl[a], tb = (p.hi[a] - ol[a]) / dl[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return -1;
  }
  return t0;
}

// A 64-beam scan (+2 to -24.8 degrees, 0.2 degree azimuth over the front 100 degrees) from a LiDAR
// 0.08 m above and 0.27 m behind the camera, KITTI axes (x forward, y left, z up).
inline void scan(Scene& s, double ground_y = 1.65, double az_step_deg = 0.2) {
  Eigen::Matrix3d R;  // LiDAR -> camera axes
  R << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  s.T_cam_lidar = Eigen::Isometry3d::Identity();
  s.T_cam_lidar.linear() = R;
  s.T_cam_lidar.translation() = Eigen::Vector3d(0, -0.08, -0.27);
  const Eigen::Vector3d o = s.T_cam_lidar.translation();
  s.lidar.clear();
  for (int beam = 0; beam < 64; ++beam) {
    const double el = (2.0 - beam * 26.8 / 63) * M_PI / 180;
    for (double az = -50; az <= 50; az += az_step_deg) {
      const double a = az * M_PI / 180;
      const Eigen::Vector3d dl(std::cos(el) * std::cos(a), std::cos(el) * std::sin(a), std::sin(el));
      const Eigen::Vector3d d = R * dl;
      double best = 1e9;
      if (d.y() > 1e-6) best = (ground_y - o.y()) / d.y();
      for (const Car& car : s.cars)
        for (const Part& p : car.parts) {
          const double t = rayPart(car, p, o, d);
          if (t > 0 && t < best) best = t;
        }
      if (best > 80) continue;
      const Eigen::Vector3d pl = best * dl;
      s.lidar.insert(s.lidar.end(),
                     {static_cast<float>(pl.x()), static_cast<float>(pl.y()), static_cast<float>(pl.z()), 0.5f});
    }
  }
}

// A street: cars parked on both sides and a few ahead, none overlapping in the image more than a little.
inline Scene street(uint32_t seed, int variant) {
  Scene s;
  s.K = kittiIntrinsics();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  int id = 1;
  const double side = (variant % 2) ? 1 : -1;
  // Parked, one per side at staggered depths (left and right), plus one ahead (driving).
  const double z1 = 8 + 4 * u(rng) + variant, z2 = 14 + 6 * u(rng) + variant;
  s.cars.push_back(makeCar(id++, side * (3.6 + 0.4 * u(rng)), z1, M_PI / 2 + 0.05 * (u(rng) - 0.5), 4.2, 1.75, 1.5, 170,
                           BESLAM_MOTION_STATIC));
  s.cars.push_back(makeCar(id++, -side * (3.8 + 0.4 * u(rng)), z2, -M_PI / 2 + 0.1 * (u(rng) - 0.5), 4.5, 1.8, 1.45, 60,
                           BESLAM_MOTION_STATIC));
  s.cars.push_back(makeCar(id++, 0.3 * (u(rng) - 0.5), 12 + 10 * u(rng),
                           M_PI / 2 + 0.2 * (u(rng) - 0.5) + (variant % 3) * 0.5, 4.0, 1.7, 1.5, 210,
                           BESLAM_MOTION_DYNAMIC));
  render(s, seed);
  scan(s);
  return s;
}

}  // namespace beslam::mask::fixture
