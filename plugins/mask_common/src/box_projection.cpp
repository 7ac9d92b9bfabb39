#include "beslam/mask_common/box_projection.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "beslam/sdk/views.hpp"

namespace beslam::mask {

Intrinsics fromCamera(const beslam_camera& camera) {
  Intrinsics K;
  K.fx = camera.fx, K.fy = camera.fy, K.cx = camera.cx, K.cy = camera.cy;
  K.width = camera.width, K.height = camera.height;
  return K;
}

std::vector<Eigen::Vector3d> clippedBoxVertices(const beslam_box3d& box, double near) {
  const Eigen::Matrix<double, 3, 8> c = sdk::boxCorners(box);
  // Edges of sdk::boxCorners' ordering: bottom face 0-1-2-3, top face 4-5-6-7, verticals i-(i+4).
  static const int kEdges[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                    {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  std::vector<Eigen::Vector3d> out;
  out.reserve(12);
  for (int i = 0; i < 8; ++i)
    if (c(2, i) >= near) out.push_back(c.col(i));
  for (const auto& e : kEdges) {
    const Eigen::Vector3d a = c.col(e[0]), b = c.col(e[1]);
    if ((a.z() - near) * (b.z() - near) < 0) {
      const double t = (near - a.z()) / (b.z() - a.z());
      Eigen::Vector3d p = a + t * (b - a);
      p.z() = near;
      out.push_back(p);
    }
  }
  return out;
}

std::vector<cv::Point2f> clipPolygonToRect(const std::vector<cv::Point2f>& polygon, const cv::Rect2f& rect) {
  std::vector<cv::Point2f> poly = polygon;
  auto clip = [&poly](auto inside, auto cross) {
    std::vector<cv::Point2f> out;
    const size_t n = poly.size();
    for (size_t i = 0; i < n; ++i) {
      const cv::Point2f& a = poly[i];
      const cv::Point2f& b = poly[(i + 1) % n];
      const bool ia = inside(a), ib = inside(b);
      if (ia) out.push_back(a);
      if (ia != ib) out.push_back(cross(a, b));
    }
    poly.swap(out);
  };
  const float x0 = rect.x, y0 = rect.y, x1 = rect.x + rect.width, y1 = rect.y + rect.height;
  auto atX = [](float x) {
    return [x](const cv::Point2f& a, const cv::Point2f& b) {
      const float t = (x - a.x) / (b.x - a.x);
      return cv::Point2f(x, a.y + t * (b.y - a.y));
    };
  };
  auto atY = [](float y) {
    return [y](const cv::Point2f& a, const cv::Point2f& b) {
      const float t = (y - a.y) / (b.y - a.y);
      return cv::Point2f(a.x + t * (b.x - a.x), y);
    };
  };
  if (!poly.empty()) clip([x0](const cv::Point2f& p) { return p.x >= x0; }, atX(x0));
  if (!poly.empty()) clip([x1](const cv::Point2f& p) { return p.x <= x1; }, atX(x1));
  if (!poly.empty()) clip([y0](const cv::Point2f& p) { return p.y >= y0; }, atY(y0));
  if (!poly.empty()) clip([y1](const cv::Point2f& p) { return p.y <= y1; }, atY(y1));
  return poly;
}

std::vector<cv::Point2f> projectBoxPolygon(const beslam_box3d& box, const Intrinsics& K, double near, double margin_px,
                                           double guard) {
  if (!(near > 0)) throw std::invalid_argument("near plane must be positive");
  const std::vector<Eigen::Vector3d> v = clippedBoxVertices(box, near);
  if (v.empty()) return {};
  std::vector<cv::Point2f> pts;
  pts.reserve(v.size() * (margin_px > 0 ? 8 : 1));
  for (const Eigen::Vector3d& p : v) {
    const Eigen::Vector2d uv = K.project(p);
    // Keep the numbers finite and small enough for float and fillPoly's fixed point (the guard clip
    // below brings them into the image anyway; clamping a vertex of a convex polygon far outside the
    // image moves only parts outside the guarded rectangle).
    const double lim = 1e6;
    const cv::Point2f q(static_cast<float>(std::clamp(uv.x(), -lim, lim)),
                        static_cast<float>(std::clamp(uv.y(), -lim, lim)));
    if (margin_px > 0) {
      for (int k = 0; k < 8; ++k) {
        const double a = k * M_PI / 4 + M_PI / 8;
        // Octagon circumscribing the disk of radius margin_px.
        const double r = margin_px / std::cos(M_PI / 8);
        pts.emplace_back(q.x + static_cast<float>(r * std::cos(a)), q.y + static_cast<float>(r * std::sin(a)));
      }
    } else {
      pts.push_back(q);
    }
  }
  std::vector<cv::Point2f> hull;
  cv::convexHull(pts, hull, /*clockwise=*/false);
  const cv::Rect2f rect(static_cast<float>(-guard), static_cast<float>(-guard),
                        static_cast<float>(K.width - 1 + 2 * guard), static_cast<float>(K.height - 1 + 2 * guard));
  std::vector<cv::Point2f> clipped = clipPolygonToRect(hull, rect);
  if (clipped.size() < 3) return {};
  // A polygon entirely in the guard band misses the image.
  float u0 = 1e30f, v0 = 1e30f, u1 = -1e30f, v1 = -1e30f;
  for (const auto& p : clipped)
    u0 = std::min(u0, p.x), u1 = std::max(u1, p.x), v0 = std::min(v0, p.y), v1 = std::max(v1, p.y);
  if (u1 < -0.5f || v1 < -0.5f || u0 > K.width - 0.5f || v0 > K.height - 0.5f) return {};
  return clipped;
}

UnknownPolicy parseUnknownPolicy(const std::string& text) {
  if (text == "dynamic") return UnknownPolicy::Dynamic;
  if (text == "static") return UnknownPolicy::Static;
  if (text == "skip") return UnknownPolicy::Skip;
  throw std::invalid_argument("unknown_policy must be dynamic, static or skip, not '" + text + "'");
}

std::optional<uint16_t> labelFor(const beslam_box3d& box, UnknownPolicy unknown) {
  const bool has_id = box.track_id >= 0 && box.track_id <= 65535 - BESLAM_LABEL_STATIC_BASE;
  switch (box.motion_state) {
    case BESLAM_MOTION_DYNAMIC:
      return static_cast<uint16_t>(BESLAM_LABEL_DYNAMIC);
    case BESLAM_MOTION_STATIC:
      return has_id ? static_cast<uint16_t>(BESLAM_LABEL_STATIC_BASE + box.track_id)
                    : static_cast<uint16_t>(BESLAM_LABEL_DYNAMIC);
    default:
      if (unknown == UnknownPolicy::Skip) return std::nullopt;
      if (unknown == UnknownPolicy::Static && has_id)
        return static_cast<uint16_t>(BESLAM_LABEL_STATIC_BASE + box.track_id);
      return static_cast<uint16_t>(BESLAM_LABEL_DYNAMIC);
  }
}

}  // namespace beslam::mask
