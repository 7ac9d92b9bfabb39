#include "beslam/mask_common/lidar.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

namespace beslam::mask {

CameraPoints lidarToCamera(const float* xyzi, size_t count, size_t stride_floats, const Eigen::Isometry3d& T_cam_lidar,
                           const Intrinsics& K, double near, double max_range) {
  CameraPoints out;
  if (xyzi == nullptr || count == 0) return out;
  if (stride_floats < 4) stride_floats = 4;
  const Eigen::Matrix3f R = T_cam_lidar.linear().cast<float>();
  const Eigen::Vector3f t = T_cam_lidar.translation().cast<float>();
  const float max_r2 = static_cast<float>(max_range * max_range);
  out.p.reserve(count / 4);
  out.uv.reserve(count / 4);
  for (size_t i = 0; i < count; ++i) {
    const float* q = xyzi + i * stride_floats;
    if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) continue;
    const Eigen::Vector3f p = R * Eigen::Vector3f(q[0], q[1], q[2]) + t;
    if (p.z() < near || p.squaredNorm() > max_r2) continue;
    const float u = static_cast<float>(K.fx * p.x() / p.z() + K.cx);
    const float v = static_cast<float>(K.fy * p.y() / p.z() + K.cy);
    if (u < -0.5f || v < -0.5f || u >= K.width - 0.5f || v >= K.height - 0.5f) continue;
    out.p.push_back(p);
    out.uv.emplace_back(u, v);
  }
  out.column_bins.assign(static_cast<size_t>(K.width / CameraPoints::kBinPx + 1), {});
  for (size_t i = 0; i < out.uv.size(); ++i) {
    const int bin = std::clamp(static_cast<int>(out.uv[i].x + 0.5f) / CameraPoints::kBinPx, 0,
                               static_cast<int>(out.column_bins.size()) - 1);
    out.column_bins[bin].push_back(static_cast<int>(i));
  }
  return out;
}

namespace {

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

struct Fit {
  double ca = 0, cb = 0, cost = 1e30;
};

// Fixed-size L-shape fit at yaw theta: points (x, z) rotated into (a, b) about the sensor (origin); the
// sides facing the sensor are put on the points' extremes, the cost is the mean distance of each point
// to the nearer of those sides (truncated) plus how far points stick out of the box.
Fit fitAtYaw(const std::vector<Eigen::Vector2d>& pts, double theta, double l, double w, double ca0, double cb0) {
  const double c = std::cos(theta), s = std::sin(theta);
  std::vector<double> a(pts.size()), b(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    a[i] = pts[i].x() * c - pts[i].y() * s;
    b[i] = pts[i].x() * s + pts[i].y() * c;
  }
  auto place = [](const std::vector<double>& v, double len, double prior, double& centre, double& face,
                  bool& has_face) {
    const double lo = percentile(v, 0.03), hi = percentile(v, 0.97);
    has_face = false;
    if (lo > 0) {
      centre = lo + len / 2, face = lo, has_face = true;
    } else if (hi < 0) {
      centre = hi - len / 2, face = hi, has_face = true;
    } else if (hi - lo > len) {
      centre = (lo + hi) / 2;
    } else {
      centre = std::clamp(prior, hi - len / 2, lo + len / 2);
    }
  };
  Fit f;
  double fa = 0, fb = 0;
  bool ha = false, hb = false;
  place(a, l, ca0, f.ca, fa, ha);
  place(b, w, cb0, f.cb, fb, hb);
  double cost = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    double d = 0.5;
    if (ha) d = std::min(d, std::abs(a[i] - fa));
    if (hb) d = std::min(d, std::abs(b[i] - fb));
    if (!ha && !hb) d = 0;
    const double out = std::max(0.0, std::abs(a[i] - f.ca) - l / 2) + std::max(0.0, std::abs(b[i] - f.cb) - w / 2);
    cost += d + 2.0 * std::min(out, 1.0);
  }
  f.cost = cost / std::max<size_t>(1, pts.size());
  return f;
}

}  // namespace

double truncatedFraction(const beslam_box3d& box, const Intrinsics& K) {
  if (K.width <= 0 || K.height <= 0) return 0.0;
  const std::vector<cv::Point2f> all = projectBoxPolygon(box, K, 0.3, 0.0, 1e5);
  if (all.size() < 3) return 1.0;
  const double area = cv::contourArea(all);
  if (area <= 0) return 1.0;
  const std::vector<cv::Point2f> in = clipPolygonToRect(all, cv::Rect2f(-0.5f, -0.5f, K.width, K.height));
  const double inside = in.size() < 3 ? 0.0 : cv::contourArea(in);
  return std::clamp(1.0 - inside / area, 0.0, 1.0);
}

std::vector<int> pointsNearBox(const beslam_box3d& box, const CameraPoints& points, double margin,
                               double ground_clearance, const Intrinsics* K) {
  std::vector<int> out;
  const double l2 = box.size[0] / 2 + margin, w2 = box.size[1] / 2 + margin;
  const double y_top = box.center_cam[1] - box.size[2] / 2 - 0.1;
  const double y_bottom = box.center_cam[1] + box.size[2] / 2 - ground_clearance;
  const double r2 = (l2 * l2 + w2 * w2);
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  auto test = [&](size_t i) {
    const Eigen::Vector3f& p = points.p[i];
    if (p.y() < y_top || p.y() > y_bottom) return;
    const double dx = p.x() - box.center_cam[0], dz = p.z() - box.center_cam[2];
    if (dx * dx + dz * dz > r2) return;
    const double a = dx * c - dz * s, b = dx * s + dz * c;
    if (std::abs(a) <= l2 && std::abs(b) <= w2) out.push_back(static_cast<int>(i));
  };
  if (K != nullptr && !points.column_bins.empty()) {
    // Only the column bands the grown box covers in the image.
    beslam_box3d grown = box;
    grown.size[0] = 2 * l2, grown.size[1] = 2 * w2, grown.size[2] += 0.2;
    const std::vector<cv::Point2f> poly = projectBoxPolygon(grown, *K, 0.3, 1.0);
    if (poly.size() < 3) return out;
    float u0 = 1e30f, u1 = -1e30f;
    for (const auto& q : poly) u0 = std::min(u0, q.x), u1 = std::max(u1, q.x);
    const int nb = static_cast<int>(points.column_bins.size());
    const int b0 = std::clamp(static_cast<int>(std::floor(u0)) / CameraPoints::kBinPx - 1, 0, nb - 1);
    const int b1 = std::clamp(static_cast<int>(std::ceil(u1)) / CameraPoints::kBinPx + 1, 0, nb - 1);
    for (int b = b0; b <= b1; ++b)
      for (int i : points.column_bins[b]) test(static_cast<size_t>(i));
    return out;
  }
  for (size_t i = 0; i < points.size(); ++i) test(i);
  return out;
}

BevRefineResult refineBoxBev(const beslam_box3d& box, const CameraPoints& points, const BevRefineParams& params) {
  BevRefineResult result;
  result.box = box;
  // A box mostly outside the image has its points cut by the field of view (only in-image points are
  // kept): the cut would pose as a face. Such boxes keep their input pose.
  if (params.max_truncation < 1.0 && truncatedFraction(box, params.intrinsics) > params.max_truncation) return result;
  const std::vector<int> cand = pointsNearBox(box, points, params.search_margin, params.ground_clearance,
                                              params.intrinsics.width > 0 ? &params.intrinsics : nullptr);
  if (static_cast<int>(cand.size()) < params.min_points) return result;

  // BEV clusters: occupied cells of cluster_gap / 2, 8-connected (two points of one cluster are linked by
  // a chain of cells; clusters farther apart than about 1.4 cluster_gap never merge). Linear time.
  const double cell_size = params.cluster_gap / 2;
  auto key = [](int cx, int cz) {  // shifted as unsigned: a left shift of a negative value is undefined
    return static_cast<int64_t>((uint64_t{static_cast<uint32_t>(cx)} << 32) | static_cast<uint32_t>(cz));
  };
  std::unordered_map<int64_t, int> cells;
  cells.reserve(cand.size());
  std::vector<int> point_cell(cand.size());
  std::vector<std::pair<int, int>> cell_xy;
  for (size_t k = 0; k < cand.size(); ++k) {
    const Eigen::Vector3f& p = points.p[cand[k]];
    const int cx = static_cast<int>(std::floor(p.x() / cell_size)),
              cz = static_cast<int>(std::floor(p.z() / cell_size));
    auto [it, inserted] = cells.try_emplace(key(cx, cz), static_cast<int>(cell_xy.size()));
    if (inserted) cell_xy.emplace_back(cx, cz);
    point_cell[k] = it->second;
  }
  std::vector<int> parent(cell_xy.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&parent](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (size_t c = 0; c < cell_xy.size(); ++c)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dz = -1; dz <= 1; ++dz) {
        const auto it = cells.find(key(cell_xy[c].first + dx, cell_xy[c].second + dz));
        if (it != cells.end()) parent[find(it->second)] = find(static_cast<int>(c));
      }
  // The cluster with the most points inside the input box.
  std::unordered_map<int, int> inside;
  const double cy = std::cos(box.yaw), sy = std::sin(box.yaw);
  for (size_t k = 0; k < cand.size(); ++k) {
    const Eigen::Vector3f& p = points.p[cand[k]];
    const double dx = p.x() - box.center_cam[0], dz = p.z() - box.center_cam[2];
    const double a = dx * cy - dz * sy, b = dx * sy + dz * cy;
    if (std::abs(a) <= box.size[0] / 2 + 0.1 && std::abs(b) <= box.size[1] / 2 + 0.1) ++inside[find(point_cell[k])];
  }
  int best = -1, best_n = 0;
  for (const auto& [root, n] : inside)
    if (n > best_n) best = root, best_n = n;
  if (best < 0) return result;
  std::vector<Eigen::Vector2d> obj;
  for (size_t k = 0; k < cand.size(); ++k)
    if (find(point_cell[k]) == best) obj.emplace_back(points.p[cand[k]].x(), points.p[cand[k]].z());
  result.points = static_cast<int>(obj.size());
  if (result.points < params.min_points) return result;

  // Outline seen from the sensor: the nearest point per 0.2 degree of azimuth (drops roof and bonnet
  // returns behind the faces the fit aligns with).
  std::unordered_map<int, int> nearest;
  for (size_t i = 0; i < obj.size(); ++i) {
    const int bin = static_cast<int>(std::floor(std::atan2(obj[i].x(), obj[i].y()) * 180.0 / M_PI / 0.2));
    auto it = nearest.find(bin);
    if (it == nearest.end() || obj[i].squaredNorm() < obj[it->second].squaredNorm()) nearest[bin] = static_cast<int>(i);
  }
  std::vector<Eigen::Vector2d> outline;
  outline.reserve(nearest.size());
  for (const auto& [bin, i] : nearest) outline.push_back(obj[i]);
  if (static_cast<int>(outline.size()) < 4) return result;

  const double l = box.size[0], w = box.size[1];
  auto prior = [&](double theta, double& ca0, double& cb0) {
    const double c = std::cos(theta), s = std::sin(theta);
    ca0 = box.center_cam[0] * c - box.center_cam[2] * s;
    cb0 = box.center_cam[0] * s + box.center_cam[2] * c;
  };
  double best_theta = box.yaw;
  Fit best_fit;
  auto evaluate = [&](double theta) {
    double ca0, cb0;
    prior(theta, ca0, cb0);
    Fit f = fitAtYaw(outline, theta, l, w, ca0, cb0);
    // Prior on the input's yaw: decides when the outline is too short or sparse to fix the heading.
    const double dyaw = std::remainder(theta - box.yaw, 2 * M_PI);
    f.cost += params.yaw_prior_weight * dyaw * dyaw;
    if (f.cost < best_fit.cost) best_fit = f, best_theta = theta;
  };
  const double range = params.yaw_range_deg * M_PI / 180.0, coarse = 1.0 * M_PI / 180.0, fine = 0.1 * M_PI / 180.0;
  if (static_cast<int>(outline.size()) < params.min_outline_for_yaw) {
    evaluate(box.yaw);  // too few returns to fix a heading: centre only
  } else {
    for (double d = -range; d <= range + 1e-9; d += coarse) evaluate(box.yaw + d);
    const double centre = best_theta;
    for (double d = -coarse; d <= coarse + 1e-9; d += fine) evaluate(centre + d);
  }

  double theta = std::remainder(best_theta, 2 * M_PI);
  const double c = std::cos(best_theta), s = std::sin(best_theta);
  result.box.center_cam[0] = c * best_fit.ca + s * best_fit.cb;
  result.box.center_cam[2] = -s * best_fit.ca + c * best_fit.cb;
  result.box.yaw = theta;
  result.refined = true;
  result.cost = best_fit.cost;
  return result;
}

cv::Mat pointMask(const CameraPoints& points, const std::vector<int>& indices, const cv::Rect& roi,
                  const cv::Mat& polygon_mask, const PointMaskParams& params) {
  if (static_cast<int>(indices.size()) < params.min_points || roi.area() <= 0) return {};
  cv::Mat splat = cv::Mat::zeros(roi.size(), CV_8UC1);
  int drawn = 0;
  for (int i : indices) {
    const int u = static_cast<int>(std::lround(points.uv[i].x)) - roi.x;
    const int v = static_cast<int>(std::lround(points.uv[i].y)) - roi.y;
    if (u < 0 || v < 0 || u >= roi.width || v >= roi.height) continue;
    const int x0 = std::max(0, u - params.splat_half_width), x1 = std::min(roi.width - 1, u + params.splat_half_width);
    const int y0 = std::max(0, v - params.splat_half_height),
              y1 = std::min(roi.height - 1, v + params.splat_half_height);
    for (int y = y0; y <= y1; ++y) std::memset(splat.ptr<uint8_t>(y) + x0, 255, static_cast<size_t>(x1 - x0 + 1));
    ++drawn;
  }
  if (drawn < params.min_points) return {};
  if (params.close_px > 0) {
    const cv::Mat k =
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * params.close_px + 1, 2 * params.close_px + 1));
    cv::morphologyEx(splat, splat, cv::MORPH_CLOSE, k);
  }
  // Fill holes: flood the background from a 1-pixel frame around the crop.
  cv::Mat padded = cv::Mat::zeros(roi.height + 2, roi.width + 2, CV_8UC1);
  splat.copyTo(padded(cv::Rect(1, 1, roi.width, roi.height)));
  cv::floodFill(padded, cv::Point(0, 0), cv::Scalar(128));
  cv::Mat filled = padded(cv::Rect(1, 1, roi.width, roi.height)) != 128;
  if (!polygon_mask.empty()) cv::bitwise_and(filled, polygon_mask, filled);
  const int area = cv::countNonZero(filled);
  const int poly_area = polygon_mask.empty() ? roi.area() : cv::countNonZero(polygon_mask);
  if (poly_area <= 0 || area < params.min_coverage * poly_area) return {};
  return filled;
}

double bevCentreError(const beslam_box3d& a, const beslam_box3d& b) {
  return std::hypot(a.center_cam[0] - b.center_cam[0], a.center_cam[2] - b.center_cam[2]);
}

double yawError(const beslam_box3d& a, const beslam_box3d& b) {
  double d = std::remainder(a.yaw - b.yaw, M_PI);
  return std::abs(d);
}

}  // namespace beslam::mask
