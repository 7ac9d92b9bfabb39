// LiDAR BEV car detector: ground removal, Euclidean clustering, L-shape box fitting (see the header).
#include "beslam/detector_lidar/lidar_detector.hpp"

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <unordered_map>

namespace beslam::detector_lidar {

namespace {

constexpr double kPi = 3.14159265358979323846;

double normalizeHalfPi(double yaw) {  // into (-pi/2, pi/2]: a single scan cannot tell front from back
  while (yaw > kPi / 2) yaw -= kPi;
  while (yaw <= -kPi / 2) yaw += kPi;
  return yaw;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("detector_lidar: " + what);
}

// Local ground of every kept point: y of the ground below it (camera frame, y down) and its height above it.
struct Ground {
  bool found = false;
  std::vector<double> ground_y;  // per input point
  std::vector<double> height;    // per input point
};

Ground ransacGround(const std::vector<Eigen::Vector3d>& p, const Options& o) {
  Ground g;
  pcl::PointCloud<pcl::PointXYZ>::Ptr candidates(new pcl::PointCloud<pcl::PointXYZ>);
  candidates->reserve(p.size());
  for (const Eigen::Vector3d& q : p)
    if (q.y() > 0.3)  // below the camera: the road cannot be above it
      candidates->push_back(
          pcl::PointXYZ(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())));
  if (candidates->size() < 30) return g;
  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setAxis(Eigen::Vector3f(0, 1, 0));
  seg.setEpsAngle(o.max_ground_tilt_deg * kPi / 180.0);
  seg.setDistanceThreshold(o.ground_threshold * 0.6);
  seg.setMaxIterations(o.ransac_iterations);
  seg.setInputCloud(candidates);
  pcl::PointIndices inliers;
  pcl::ModelCoefficients coefficients;
  seg.segment(inliers, coefficients);
  if (inliers.indices.size() < 20 || coefficients.values.size() != 4) return g;
  Eigen::Vector3d n(coefficients.values[0], coefficients.values[1], coefficients.values[2]);
  double d = coefficients.values[3];
  const double norm = n.norm();
  if (!(norm > 0)) return g;
  n /= norm, d /= norm;
  if (n.y() > 0) n = -n, d = -d;  // normal pointing up (camera y is down)
  if (std::abs(n.y()) < std::cos(o.max_ground_tilt_deg * kPi / 180.0 + 0.02)) return g;
  g.found = true;
  g.ground_y.resize(p.size());
  g.height.resize(p.size());
  for (size_t i = 0; i < p.size(); ++i) {
    g.height[i] = n.dot(p[i]) + d;
    g.ground_y[i] = -(n.x() * p[i].x() + n.z() * p[i].z() + d) / n.y();
  }
  return g;
}

Ground gridGround(const std::vector<Eigen::Vector3d>& p, const Options& o) {
  Ground g;
  if (p.empty()) return g;
  auto key = [](int64_t ix, int64_t iz) {
    return (static_cast<uint64_t>(ix) << 32) ^ (static_cast<uint64_t>(iz) & 0xffffffffULL);
  };
  auto cell = [&](double v) { return static_cast<int64_t>(std::floor(v / o.grid_cell)); };
  std::unordered_map<uint64_t, double> lowest;  // largest y (lowest point) per cell
  lowest.reserve(p.size() / 4 + 1);
  for (const Eigen::Vector3d& q : p) {
    auto [it, inserted] = lowest.emplace(key(cell(q.x()), cell(q.z())), q.y());
    if (!inserted) it->second = std::max(it->second, q.y());
  }
  std::unordered_map<uint64_t, double> ground;  // lowest point over the neighbourhood
  ground.reserve(lowest.size());
  g.ground_y.resize(p.size());
  g.height.resize(p.size());
  for (size_t i = 0; i < p.size(); ++i) {
    const int64_t ix = cell(p[i].x()), iz = cell(p[i].z());
    auto it = ground.find(key(ix, iz));
    if (it == ground.end()) {
      double y = -std::numeric_limits<double>::infinity();
      for (int dx = -o.grid_radius; dx <= o.grid_radius; ++dx)
        for (int dz = -o.grid_radius; dz <= o.grid_radius; ++dz) {
          auto l = lowest.find(key(ix + dx, iz + dz));
          if (l != lowest.end()) y = std::max(y, l->second);
        }
      it = ground.emplace(key(ix, iz), y).first;
    }
    g.ground_y[i] = it->second;
    g.height[i] = it->second - p[i].y();
  }
  g.found = true;
  return g;
}

// One point per occupied voxel (the first seen): bounds the clustering cost on dense near objects.
// Returns the indices of the kept points.
std::vector<size_t> voxelDownsample(const std::vector<Eigen::Vector3d>& p, double voxel) {
  std::unordered_map<uint64_t, size_t> seen;
  seen.reserve(p.size());
  std::vector<size_t> kept;
  kept.reserve(p.size());
  for (size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d& q = p[i];
    const uint64_t ix = static_cast<uint64_t>(static_cast<int64_t>(std::floor(q.x() / voxel)) & 0x1fffff);
    const uint64_t iy = static_cast<uint64_t>(static_cast<int64_t>(std::floor(q.y() / voxel)) & 0x1fffff);
    const uint64_t iz = static_cast<uint64_t>(static_cast<int64_t>(std::floor(q.z() / voxel)) & 0x1fffff);
    if (seen.emplace((ix << 42) | (iy << 21) | iz, kept.size()).second) kept.push_back(i);
  }
  return kept;
}

// BEV distance of q (camera frame x, z) from the ray from the camera along the unit direction e.
double distanceToRay(const Eigen::Vector2d& q, const Eigen::Vector2d& e) {
  const double along = q.dot(e);
  return along <= 0 ? q.norm() : (q - along * e).norm();
}

// The LiDAR rays of one scan in the BEV, binned by azimuth around the sensor, for free-space queries: a ray
// that reached a return at BEV range R passed through every place before it (up to a small gap) where its
// height above the ground was inside [min_height, max_height], where a car's body would have stopped it.
class FreeSpace {
 public:
  FreeSpace(const Eigen::Vector2d& sensor, double sensor_height, const Options& o)
      : sensor_(sensor), sensor_height_(sensor_height), o_(o), bins_(kBins) {}

  void add(const Eigen::Vector2d& p_bev, double height) {
    const Eigen::Vector2d d = p_bev - sensor_;
    const double range = d.norm();
    if (range < 0.5) return;
    // Range interval along the ray (in the BEV) over which it is within the body heights.
    const double h0 = sensor_height_, h1 = height;
    double ra = 0, rb = range - kEndGap;
    if (std::abs(h1 - h0) < 1e-9) {
      if (h0 < o_.free_space_min_height || h0 > o_.free_space_max_height) return;
    } else {
      double r_min = range * (o_.free_space_min_height - h0) / (h1 - h0);
      double r_max = range * (o_.free_space_max_height - h0) / (h1 - h0);
      if (r_min > r_max) std::swap(r_min, r_max);
      ra = std::max(ra, r_min), rb = std::min(rb, r_max);
    }
    if (rb - ra < 0.05) return;
    bins_[bin(std::atan2(d.x(), d.y()))].push_back(Ray{d / range, ra, rb});
  }

  // How far (m) a box side can move beyond `edge` along the unit direction u (sensor-relative coordinate
  // edge = (x - sensor).u) before free space contradicts it, looking at most max_grow ahead; the band
  // across it spans [lo_v, hi_v] along v (sensor-relative). max_grow when too few rays pass through.
  double room(const Eigen::Vector2d& u, double edge, const Eigen::Vector2d& v, double lo_v, double hi_v,
              double max_grow) const {
    const double a_u = edge + kStartGap, b_u = edge + max_grow;
    if (b_u <= a_u) return max_grow;
    // Azimuth span of the region.
    const Eigen::Vector2d corners[4] = {a_u * u + lo_v * v, a_u * u + hi_v * v, b_u * u + lo_v * v, b_u * u + hi_v * v};
    const Eigen::Vector2d mid = 0.5 * (corners[0] + corners[3]);
    const double a_mid = std::atan2(mid.x(), mid.y());
    double lo_a = 0, hi_a = 0;
    for (const Eigen::Vector2d& c : corners) {
      double da = std::atan2(c.x(), c.y()) - a_mid;
      while (da > kPi) da -= 2 * kPi;
      while (da < -kPi) da += 2 * kPi;
      lo_a = std::min(lo_a, da), hi_a = std::max(hi_a, da);
    }
    const bool around = hi_a - lo_a > kPi - 0.1;  // the region wraps around the sensor
    const int first = around ? 0 : bin(a_mid + lo_a), last = around ? kBins - 1 : bin(a_mid + hi_a);
    const int count = around ? kBins : (last - first + kBins) % kBins + 1;
    std::vector<double> offsets;
    for (int k = 0; k < count; ++k) {
      for (const Ray& ray : bins_[(first + k) % kBins]) {
        // Clip the free part of the ray [ra, rb] to the region's slabs along u and v.
        double t0 = ray.ra, t1 = ray.rb;
        const double du = ray.dir.dot(u), dv = ray.dir.dot(v);
        auto clip = [&](double d, double lo, double hi) {
          if (std::abs(d) < 1e-12) {
            if (lo > 0 || hi < 0) t1 = -1;
            return;
          }
          double e0 = lo / d, e1 = hi / d;
          if (e0 > e1) std::swap(e0, e1);
          t0 = std::max(t0, e0), t1 = std::min(t1, e1);
        };
        clip(du, a_u, b_u);
        clip(dv, lo_v, hi_v);
        if (t1 - t0 < 0.05) continue;
        offsets.push_back(std::min(t0 * du, t1 * du) - edge);
      }
    }
    const size_t k = static_cast<size_t>(std::max(1, o_.free_space_min_rays));
    if (offsets.size() < k) return max_grow;
    std::nth_element(offsets.begin(), offsets.begin() + static_cast<long>(k - 1), offsets.end());
    return std::clamp(offsets[k - 1], 0.0, max_grow);
  }

 private:
  static constexpr int kBins = 1440;         // 0.25 degrees
  static constexpr double kEndGap = 0.2;     // m before a return that do not count as passed through
  static constexpr double kStartGap = 0.15;  // m beyond a seen side before free space counts
  struct Ray {
    Eigen::Vector2d dir;  // unit BEV direction from the sensor
    double ra, rb;        // BEV range interval that is free at body height
  };
  static int bin(double azimuth) {
    int b = static_cast<int>(std::floor((azimuth + kPi) / (2 * kPi) * kBins));
    return ((b % kBins) + kBins) % kBins;
  }
  Eigen::Vector2d sensor_;
  double sensor_height_;
  const Options& o_;
  std::vector<std::vector<Ray>> bins_;
};

struct Cluster {
  std::vector<Eigen::Vector2d> bev;  // (x, z)
  double ground_y = 0, top = -1e9, bottom = 1e9;
};

// Completes a fitted footprint (axis[0] the longer side) to a car: per side of the rectangle, the free space
// says how far it can extend beyond what was seen. Either side can be the car's length; the one whose
// completion (each extent grown toward its prior as far as the free space allows) is closer to the prior
// size wins. Growth goes first to the end away from the sensor (its own shadow) as far as the free space
// there allows, the rest to the near end (hidden by an occluder, the image border or the blind zone).
void completeWithFreeSpace(const FreeSpace& fs, const Eigen::Vector2d& sensor, const Options& o,
                           Eigen::Vector2d& center, Eigen::Vector2d axis[2], double extent[2]) {
  const double max_grow = std::max(o.car_size[0], o.car_size[1]);
  double lo[2], hi[2], room[2][2];  // sensor-relative extents, room at the low / high end per axis
  for (int k = 0; k < 2; ++k) {
    const double mid = (center - sensor).dot(axis[k]);
    lo[k] = mid - extent[k] / 2, hi[k] = mid + extent[k] / 2;
  }
  for (int k = 0; k < 2; ++k) {
    const int j = 1 - k;
    // The band the grown part would occupy across axis k: the seen extent along j, trimmed off the seen
    // sides (rays grazing them), at least 0.6 m wide, widened away from the sensor (the hidden body).
    double band_lo = lo[j] + 0.1, band_hi = hi[j] - 0.1;
    if (band_hi - band_lo < 0.6) {
      if (lo[j] >= 0)
        band_lo = lo[j] + 0.05, band_hi = band_lo + 0.6;
      else if (hi[j] <= 0)
        band_hi = hi[j] - 0.05, band_lo = band_hi - 0.6;
      else
        band_lo = (lo[j] + hi[j]) / 2 - 0.3, band_hi = band_lo + 0.6;
    }
    room[k][1] = fs.room(axis[k], hi[k], axis[j], band_lo, band_hi, max_grow);
    room[k][0] = fs.room(-axis[k], -lo[k], axis[j], band_lo, band_hi, max_grow);
  }
  auto grown = [&](int k, double prior) { return std::clamp(prior - extent[k], 0.0, room[k][0] + room[k][1]); };
  auto cost = [&](int length_axis) {
    const int w = 1 - length_axis;
    if (extent[length_axis] > o.car_max_length || extent[w] > o.car_max_width) return 1e9;
    const double l = extent[length_axis] + grown(length_axis, o.car_size[0]), wd = extent[w] + grown(w, o.car_size[1]);
    return std::abs(std::log(l / o.car_size[0])) + std::abs(std::log(wd / o.car_size[1]));
  };
  // Car widths alone spread about 15 % around the prior (log 1.15 = 0.14): closer costs do not decide.
  constexpr double kTie = 0.15;
  const double cost_keep = cost(0), cost_swap = cost(1);
  bool swap = cost_swap < cost_keep - kTie;
  if (std::abs(cost_swap - cost_keep) <= kTie) {
    // Either way fits: the car is seen end-on, its length along the line of sight.
    const Eigen::Vector2d ray = (center - sensor).normalized();
    swap = std::abs(axis[1].dot(ray)) > std::abs(axis[0].dot(ray));
  }
  if (swap) {
    std::swap(axis[0], axis[1]), std::swap(extent[0], extent[1]), std::swap(lo[0], lo[1]), std::swap(hi[0], hi[1]);
    std::swap(room[0][0], room[1][0]), std::swap(room[0][1], room[1][1]);
  }
  for (int k = 0; k < 2; ++k) {
    double need = grown(k, o.car_size[static_cast<size_t>(k)]);
    if (need <= 0) continue;
    double grow_lo = 0, grow_hi = 0;
    if (lo[k] < 0 && hi[k] > 0) {  // the sensor is inside the slab: no far end, both halves
      grow_lo = std::min(need / 2, room[k][0]), grow_hi = std::min(need / 2, room[k][1]);
    }
    const bool far_is_hi = lo[k] + hi[k] >= 0;
    double& far = far_is_hi ? grow_hi : grow_lo;
    double& near = far_is_hi ? grow_lo : grow_hi;
    const double far_room = room[k][far_is_hi ? 1 : 0], near_room = room[k][far_is_hi ? 0 : 1];
    far = std::min(far_room, far + (need - grow_lo - grow_hi));
    near = std::min(near_room, near + (need - grow_lo - grow_hi));
    center += (grow_hi - grow_lo) / 2 * axis[k];
    extent[k] += grow_lo + grow_hi;
  }
}

}  // namespace

void Options::validate() const {
  require(min_range >= 0 && max_range > min_range, "max_range must exceed min_range >= 0");
  require(fov_margin_px >= 0, "fov_margin_px must be >= 0");
  require(fov_context >= 0, "fov_context must be >= 0");
  require(ground_method == "ransac" || ground_method == "grid",
          "ground_method must be ransac or grid, not '" + ground_method + "'");
  require(ground_threshold > 0, "ground_threshold must be > 0");
  require(max_ground_tilt_deg > 0 && max_ground_tilt_deg < 45, "max_ground_tilt_deg must be in (0, 45)");
  require(ransac_iterations > 0, "ransac_iterations must be > 0");
  require(grid_cell > 0 && grid_radius >= 0, "grid_cell must be > 0 and grid_radius >= 0");
  require(max_height > ground_threshold, "max_height must exceed ground_threshold");
  require(cluster_tolerance > 0, "cluster_tolerance must be > 0");
  require(voxel_size >= 0 && voxel_size < cluster_tolerance, "voxel_size must be in [0, cluster_tolerance)");
  require(min_cluster_points >= 3 && max_cluster_points >= min_cluster_points,
          "need 3 <= min_cluster_points <= max_cluster_points");
  require(box_fit == "lshape" || box_fit == "min_area", "box_fit must be lshape or min_area, not '" + box_fit + "'");
  require(angle_step_deg > 0 && angle_step_deg <= 45, "angle_step_deg must be in (0, 45]");
  require(lshape_min_points >= 0, "lshape_min_points must be >= 0");
  require(car_min_extent > 0 && car_max_length >= car_min_extent && car_max_width > 0, "bad car footprint limits");
  require(car_max_top > car_min_top && car_max_bottom >= 0, "bad car height limits");
  require(car_min_length > 0 && car_min_width > 0, "car_min_length and car_min_width must be > 0");
  require(car_size[0] > 0 && car_size[1] > 0 && car_size[2] > 0, "car_size must be positive");
  require(free_space_min_height >= 0 && free_space_max_height > free_space_min_height,
          "need 0 <= free_space_min_height < free_space_max_height");
  require(free_space_min_rays >= 1, "free_space_min_rays must be >= 1");
  require(uncertain_range > 0 && uncertain_points >= 0, "bad uncertainty limits");
}

Rect2 fitLShape(const std::vector<Eigen::Vector2d>& points, double step_deg) {
  if (points.size() < 2) throw std::invalid_argument("fitLShape: need at least two points");
  const int steps = std::max(1, static_cast<int>(std::lround(90.0 / step_deg)));
  const double d0 = 0.01;
  double best_score = -1, best_theta = 0;
  std::vector<double> c1(points.size()), c2(points.size());
  for (int s = 0; s < steps; ++s) {
    const double theta = s * (kPi / 2) / steps;
    const Eigen::Vector2d e1(std::cos(theta), std::sin(theta)), e2(-std::sin(theta), std::cos(theta));
    double min1 = 1e18, max1 = -1e18, min2 = 1e18, max2 = -1e18;
    for (size_t i = 0; i < points.size(); ++i) {
      c1[i] = points[i].dot(e1), c2[i] = points[i].dot(e2);
      min1 = std::min(min1, c1[i]), max1 = std::max(max1, c1[i]);
      min2 = std::min(min2, c2[i]), max2 = std::max(max2, c2[i]);
    }
    // Per axis, the side the points hug (smaller summed squared distance), then closeness to the nearer one.
    double to_min1 = 0, to_max1 = 0, to_min2 = 0, to_max2 = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      to_min1 += (c1[i] - min1) * (c1[i] - min1), to_max1 += (max1 - c1[i]) * (max1 - c1[i]);
      to_min2 += (c2[i] - min2) * (c2[i] - min2), to_max2 += (max2 - c2[i]) * (max2 - c2[i]);
    }
    const bool use_min1 = to_min1 < to_max1, use_min2 = to_min2 < to_max2;
    double score = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      const double d1 = use_min1 ? c1[i] - min1 : max1 - c1[i];
      const double d2 = use_min2 ? c2[i] - min2 : max2 - c2[i];
      score += 1.0 / std::max(std::min(d1, d2), d0);
    }
    if (score > best_score) best_score = score, best_theta = theta;
  }
  const Eigen::Vector2d e1(std::cos(best_theta), std::sin(best_theta)), e2(-std::sin(best_theta), std::cos(best_theta));
  double min1 = 1e18, max1 = -1e18, min2 = 1e18, max2 = -1e18;
  for (const Eigen::Vector2d& q : points) {
    min1 = std::min(min1, q.dot(e1)), max1 = std::max(max1, q.dot(e1));
    min2 = std::min(min2, q.dot(e2)), max2 = std::max(max2, q.dot(e2));
  }
  Rect2 r;
  r.axis = e1;
  r.extent_axis = max1 - min1;
  r.extent_cross = max2 - min2;
  r.center = 0.5 * (min1 + max1) * e1 + 0.5 * (min2 + max2) * e2;
  return r;
}

Rect2 fitMinAreaRect(const std::vector<Eigen::Vector2d>& points) {
  if (points.size() < 2) throw std::invalid_argument("fitMinAreaRect: need at least two points");
  std::vector<cv::Point2f> cv_points;
  cv_points.reserve(points.size());
  for (const Eigen::Vector2d& q : points) cv_points.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
  const cv::RotatedRect rr = cv::minAreaRect(cv_points);
  Rect2 r;
  const double a = rr.angle * kPi / 180.0;
  r.axis = Eigen::Vector2d(std::cos(a), std::sin(a));
  r.extent_axis = rr.size.width;
  r.extent_cross = rr.size.height;
  r.center = Eigen::Vector2d(rr.center.x, rr.center.y);
  return r;
}

LidarDetector::LidarDetector(const Options& options, const Eigen::Isometry3d& T_cam_lidar,
                             const std::optional<beslam_camera>& camera)
    : options_(options), T_cam_lidar_(T_cam_lidar), camera_(camera) {
  options_.validate();
  if (!T_cam_lidar_.matrix().allFinite()) throw std::invalid_argument("detector_lidar: T_cam_lidar is not finite");
  if (camera_ && (camera_->width <= 0 || camera_->height <= 0 || !(camera_->fx > 0) || !(camera_->fy > 0)))
    camera_.reset();  // no usable intrinsics: no field-of-view selection
}

namespace {

// The kept points in the camera frame and whether each is in the image's view.
struct Selection {
  std::vector<Eigen::Vector3d> p;
  std::vector<char> in_view;
};

// 1. Selection, in the camera frame. With a camera, points inside the image's view wedge (in the BEV) are
// "in view"; points up to fov_context outside it are kept too, to shape boxes cut by the image border.
Selection selectPoints(const float* xyzi, std::size_t count, std::size_t stride_floats, const Eigen::Matrix3d& R,
                       const Eigen::Vector3d& t, const std::optional<beslam_camera>& camera, const Options& o,
                       Stats& stats) {
  const bool use_fov = o.camera_fov_only && camera.has_value();
  double tan_left = 0, tan_right = 0;
  Eigen::Vector2d edge_left = Eigen::Vector2d::Zero(), edge_right = Eigen::Vector2d::Zero();
  if (use_fov) {
    tan_left = (-o.fov_margin_px - camera->cx) / camera->fx;
    tan_right = (camera->width + o.fov_margin_px - camera->cx) / camera->fx;
    edge_left = Eigen::Vector2d(tan_left, 1).normalized(), edge_right = Eigen::Vector2d(tan_right, 1).normalized();
  }
  Selection s;
  std::vector<Eigen::Vector3d>& p = s.p;
  std::vector<char>& in_view = s.in_view;
  p.reserve(count);
  in_view.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const float* q = xyzi + i * stride_floats;
    if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) {
      ++stats.invalid_points;
      continue;
    }
    const Eigen::Vector3d p_lidar(q[0], q[1], q[2]);
    const double range = p_lidar.norm();
    if (range < o.min_range || range > o.max_range) continue;
    const Eigen::Vector3d p_cam = R * p_lidar + t;
    bool inside = true;
    if (use_fov) {
      inside = p_cam.z() >= 0.5 && p_cam.x() >= tan_left * p_cam.z() && p_cam.x() <= tan_right * p_cam.z();
      if (!inside) {
        const Eigen::Vector2d q_bev(p_cam.x(), p_cam.z());
        if (o.fov_context <= 0 || p_cam.z() < -o.fov_context ||
            std::min(distanceToRay(q_bev, edge_left), distanceToRay(q_bev, edge_right)) > o.fov_context)
          continue;
      }
    }
    p.push_back(p_cam);
    in_view.push_back(inside);
  }
  stats.used_points = p.size();
  if (o.voxel_size > 0) {
    const std::vector<size_t> kept = voxelDownsample(p, o.voxel_size);
    std::vector<Eigen::Vector3d> p_kept(kept.size());
    std::vector<char> in_view_kept(kept.size());
    for (size_t k = 0; k < kept.size(); ++k) p_kept[k] = p[kept[k]], in_view_kept[k] = in_view[kept[k]];
    p.swap(p_kept), in_view.swap(in_view_kept);
  }
  return s;
}

// 2. The points above the ground and below max_height, as a cloud; object_index maps them back to p.
pcl::PointCloud<pcl::PointXYZ>::Ptr objectPoints(const std::vector<Eigen::Vector3d>& p, const Ground& ground,
                                                 const Options& o, Stats& stats, std::vector<size_t>& object_index) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr objects(new pcl::PointCloud<pcl::PointXYZ>);
  for (size_t i = 0; i < p.size(); ++i) {
    if (ground.height[i] <= o.ground_threshold) {
      ++stats.ground_points;
      continue;
    }
    if (ground.height[i] > o.max_height) continue;
    objects->push_back(
        pcl::PointXYZ(static_cast<float>(p[i].x()), static_cast<float>(p[i].y()), static_cast<float>(p[i].z())));
    object_index.push_back(i);
  }
  stats.object_points = objects->size();
  return objects;
}

// 3. Clusters: Euclidean clustering of the object points.
std::vector<pcl::PointIndices> euclideanClusters(const pcl::PointCloud<pcl::PointXYZ>::Ptr& objects, const Options& o) {
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(objects);
  std::vector<pcl::PointIndices> cluster_indices;
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
  ec.setClusterTolerance(o.cluster_tolerance);
  ec.setMinClusterSize(o.min_cluster_points);
  ec.setMaxClusterSize(o.max_cluster_points);
  ec.setSearchMethod(tree);
  ec.setInputCloud(objects);
  ec.extract(cluster_indices);
  return cluster_indices;
}

// The free space round the sensor (t: the LiDAR origin in the camera frame) from all kept points.
void buildFreeSpace(const std::vector<Eigen::Vector3d>& p, const Ground& ground, const Eigen::Vector2d& sensor,
                    const Eigen::Vector3d& t, const Options& o, std::optional<FreeSpace>& free_space) {
  // The sensor's height above the ground: the ground below the nearby points, seen from the sensor.
  std::vector<double> below;
  for (size_t i = 0; i < p.size(); ++i)
    if ((Eigen::Vector2d(p[i].x(), p[i].z()) - sensor).squaredNorm() < 15.0 * 15.0)
      below.push_back(ground.ground_y[i] - t.y());
  double sensor_height = 1.73;
  if (!below.empty()) {
    std::nth_element(below.begin(), below.begin() + static_cast<long>(below.size() / 2), below.end());
    sensor_height = below[below.size() / 2];
  }
  free_space.emplace(sensor, sensor_height, o);
  for (size_t i = 0; i < p.size(); ++i) free_space->add(Eigen::Vector2d(p[i].x(), p[i].z()), ground.height[i]);
}

// Without free space: orients a footprint seen end-on along the line of sight, and grows the sides the
// sensor cannot have measured away from it, up to the prior car size (fit_center: the fitted rectangle's).
void growHiddenSides(const Eigen::Vector2d& sensor, const Options& o, const Eigen::Vector2d& fit_center,
                     Eigen::Vector2d& center, Eigen::Vector2d axis[2], double extent[2]) {
  if (extent[0] <= o.car_size[1] + 0.5) {
    // No side is longer than a car is wide: the car is seen from behind or ahead, so its length runs
    // along the line of sight (the axis closer to the viewing ray).
    const Eigen::Vector2d ray = (fit_center - sensor).normalized();
    if (std::abs(axis[1].dot(ray)) > std::abs(axis[0].dot(ray)))
      std::swap(axis[0], axis[1]), std::swap(extent[0], extent[1]);
  }
  // Grow sides the sensor cannot have measured away from it, up to the prior. A side along axis k is
  // measured when the sensor looks at the face parallel to it (it lies outside the box's slab across k)
  // and the cluster spans a plausible car length (width) along it; otherwise part of it is hidden.
  for (int k = 0; k < 2; ++k) {
    const double prior = o.car_size[static_cast<size_t>(k)];
    if (extent[k] >= prior) continue;
    const int j = 1 - k;
    const double across = std::abs((sensor - center).dot(axis[j]));
    const double plausible = k == 0 ? o.car_min_length : o.car_min_width;
    if (extent[k] >= plausible && across > extent[j] / 2 + 0.1) continue;
    const double mid = (center - sensor).dot(axis[k]);
    const double lo = mid - extent[k] / 2, hi = mid + extent[k] / 2;
    double new_lo = lo, new_hi = hi;
    if (lo >= 0)
      new_hi = lo + prior;
    else if (hi <= 0)
      new_lo = hi - prior;
    else
      new_lo = mid - prior / 2, new_hi = mid + prior / 2;
    center += ((new_lo + new_hi) / 2 - mid) * axis[k];
    extent[k] = prior;
  }
}

// 4-5. Fit, gate, grow: the car box of one cluster, or none where it is wholly outside the image or its
// height or footprint does not fit a car.
std::optional<beslam_box3d> clusterBox(const pcl::PointIndices& indices, const std::vector<size_t>& object_index,
                                       const Selection& sel, const Ground& ground,
                                       const std::optional<FreeSpace>& free_space, const Eigen::Vector2d& sensor,
                                       const Options& o) {
  const std::vector<Eigen::Vector3d>& p = sel.p;
  const std::vector<char>& in_view = sel.in_view;
  Cluster c;
  double ground_sum = 0;
  int seen_in_view = 0;
  for (int k : indices.indices) {
    const size_t i = object_index[static_cast<size_t>(k)];
    c.bev.emplace_back(p[i].x(), p[i].z());
    ground_sum += ground.ground_y[i];
    c.top = std::max(c.top, ground.height[i]);
    c.bottom = std::min(c.bottom, ground.height[i]);
    seen_in_view += in_view[i];
  }
  if (seen_in_view == 0) return std::nullopt;  // wholly outside the image
  c.ground_y = ground_sum / static_cast<double>(indices.indices.size());
  if (c.top < o.car_min_top || c.top > o.car_max_top || c.bottom > o.car_max_bottom) return std::nullopt;
  // The closeness criterion needs enough points along both sides; sparse (far) clusters get the
  // minimum-area rectangle.
  const bool lshape = o.box_fit == "lshape" && static_cast<int>(c.bev.size()) >= o.lshape_min_points;
  Rect2 r = lshape ? fitLShape(c.bev, o.angle_step_deg) : fitMinAreaRect(c.bev);

  // Axis 0: the length axis, axis 1: the width axis.
  Eigen::Vector2d axis[2] = {r.axis, Eigen::Vector2d(-r.axis.y(), r.axis.x())};
  double extent[2] = {r.extent_axis, r.extent_cross};
  if (extent[1] > extent[0]) std::swap(axis[0], axis[1]), std::swap(extent[0], extent[1]);
  if (extent[0] < o.car_min_extent || extent[0] > o.car_max_length || extent[1] > o.car_max_width) return std::nullopt;
  Eigen::Vector2d center = r.center;
  if (free_space && lshape)
    completeWithFreeSpace(*free_space, sensor, o, center, axis, extent);
  else
    growHiddenSides(sensor, o, r.center, center, axis, extent);

  beslam_box3d box{};
  box.class_id = BESLAM_CLASS_CAR;
  box.track_id = -1;
  box.motion_state = BESLAM_MOTION_UNKNOWN;
  const double height = std::max(c.top, 0.5);
  box.center_cam[0] = center.x();
  box.center_cam[1] = c.ground_y - height / 2;
  box.center_cam[2] = center.y();
  box.size[0] = extent[0];
  box.size[1] = extent[1];
  box.size[2] = height;
  box.yaw = normalizeHalfPi(std::atan2(-axis[0].y(), axis[0].x()));  // heading (x, z) = (cos ry, -sin ry)
  const double n_points = static_cast<double>(c.bev.size());
  box.score = static_cast<float>(std::min(1.0, 0.3 + 0.7 * n_points / 80.0));
  const double range = (center - sensor).norm();
  if (range > o.uncertain_range || n_points < o.uncertain_points) box.flags |= BESLAM_BOX_UNCERTAIN;
  return box;
}

}  // namespace

std::vector<beslam_box3d> LidarDetector::detect(const float* xyzi, std::size_t count, std::size_t stride_floats,
                                                Stats* stats_out) const {
  const Options& o = options_;
  Stats stats;
  stats.input_points = count;
  std::vector<beslam_box3d> boxes;
  if (xyzi == nullptr || count == 0) {
    if (stats_out) *stats_out = stats;
    return boxes;
  }
  if (stride_floats < 4) throw std::invalid_argument("detector_lidar: point stride below 4 floats");

  // 1. Selection.
  const Eigen::Matrix3d R = T_cam_lidar_.linear();
  const Eigen::Vector3d t = T_cam_lidar_.translation();
  const Selection sel = selectPoints(xyzi, count, stride_floats, R, t, camera_, o, stats);
  const std::vector<Eigen::Vector3d>& p = sel.p;

  // 2. Ground.
  Ground ground = o.ground_method == "ransac" ? ransacGround(p, o) : Ground{};
  if (!ground.found) ground = gridGround(p, o);
  stats.ground_found = ground.found;
  if (!ground.found) {
    if (stats_out) *stats_out = stats;
    return boxes;
  }
  std::vector<size_t> object_index;
  const pcl::PointCloud<pcl::PointXYZ>::Ptr objects = objectPoints(p, ground, o, stats, object_index);
  if (objects->size() < static_cast<size_t>(o.min_cluster_points)) {
    if (stats_out) *stats_out = stats;
    return boxes;
  }

  // 3. Clusters.
  const std::vector<pcl::PointIndices> cluster_indices = euclideanClusters(objects, o);
  stats.clusters = cluster_indices.size();

  // 4-5. Fit, gate, grow.
  const Eigen::Vector2d sensor(t.x(), t.z());  // LiDAR origin in the BEV
  std::optional<FreeSpace> free_space;
  if (o.free_space) buildFreeSpace(p, ground, sensor, t, o, free_space);
  for (const pcl::PointIndices& indices : cluster_indices)
    if (const auto box = clusterBox(indices, object_index, sel, ground, free_space, sensor, o)) boxes.push_back(*box);
  std::sort(boxes.begin(), boxes.end(), [](const beslam_box3d& a, const beslam_box3d& b) {
    return a.center_cam[0] * a.center_cam[0] + a.center_cam[2] * a.center_cam[2] <
           b.center_cam[0] * b.center_cam[0] + b.center_cam[2] * b.center_cam[2];
  });
  stats.cars = boxes.size();
  if (stats_out) *stats_out = stats;
  return boxes;
}

}  // namespace beslam::detector_lidar
