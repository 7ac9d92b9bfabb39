// Internal: a z-buffer triangle rasteriser over view-frame triangles (x right, y down, z forward).
// Depth is stored as 1/z, which is affine in screen space, so every pixel gets the exact plane depth.
// Pixel centres are at integer coordinates (OpenCV / KITTI convention).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace beslam::sim::detail {

struct RasterTarget {
  int W = 0, H = 0;
  float fx = 1, fy = 1, cx = 0, cy = 0;
  float near = 0.1f;
  std::vector<float> invz;       // 0 = nothing
  std::vector<std::int32_t> id;  // -1 = nothing
  void reset(int w, int h) {
    W = w, H = h;
    invz.assign(static_cast<std::size_t>(w) * h, 0.f);
    id.assign(static_cast<std::size_t>(w) * h, -1);
  }
};

// Clips the triangle to the view frustum and calls span(y, x0, x1, A, B, C) for every covered row,
// where 1/z = A x + B y + C. Returns false when the triangle is invisible or degenerate.
template <class Span>
bool rasterizeTriangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c,
                       const RasterTarget& t, Span&& span) {
  const Eigen::Vector3f n = (b - a).cross(c - a);
  const float d = n.dot(a);
  if (std::abs(d) < 1e-7f * n.norm() || n.squaredNorm() == 0.f) return false;
  const float A = n.x() / (t.fx * d), B = n.y() / (t.fy * d),
              C = (n.z() - n.x() * t.cx / t.fx - n.y() * t.cy / t.fy) / d;
  // Clip polygon in view space against near and the four side planes (1 px guard band).
  float poly[2][12][3];
  int count = 3;
  const Eigen::Vector3f* v[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) poly[0][i][k] = (*v[i])[k];
  const float g = 1.0f;
  const float planes[5][4] = {{0, 0, 1, -t.near},
                              {t.fx, 0, t.cx + g, 0},
                              {-t.fx, 0, t.W - 1 + g - t.cx, 0},
                              {0, t.fy, t.cy + g, 0},
                              {0, -t.fy, t.H - 1 + g - t.cy, 0}};
  int cur = 0;
  for (const auto& pl : planes) {
    int out = 0;
    const int nxt = cur ^ 1;
    for (int i = 0; i < count; ++i) {
      const float* p = poly[cur][i];
      const float* q = poly[cur][(i + 1) % count];
      const float dp = pl[0] * p[0] + pl[1] * p[1] + pl[2] * p[2] + pl[3];
      const float dq = pl[0] * q[0] + pl[1] * q[1] + pl[2] * q[2] + pl[3];
      if (dp >= 0 && out < 12) {
        for (int k = 0; k < 3; ++k) poly[nxt][out][k] = p[k];
        ++out;
      }
      if ((dp >= 0) != (dq >= 0) && out < 12) {
        const float s = dp / (dp - dq);
        for (int k = 0; k < 3; ++k) poly[nxt][out][k] = p[k] + s * (q[k] - p[k]);
        ++out;
      }
    }
    count = out;
    cur = nxt;
    if (count < 3) return false;
  }
  float sx[12], sy[12];
  float ymin = 1e30f, ymax = -1e30f;
  for (int i = 0; i < count; ++i) {
    const float* p = poly[cur][i];
    const float iz = 1.f / p[2];
    sx[i] = t.fx * p[0] * iz + t.cx;
    sy[i] = t.fy * p[1] * iz + t.cy;
    ymin = std::min(ymin, sy[i]);
    ymax = std::max(ymax, sy[i]);
  }
  const int y0 = std::max(0, static_cast<int>(std::ceil(ymin - 1e-4f)));
  const int y1 = std::min(t.H - 1, static_cast<int>(std::floor(ymax + 1e-4f)));
  for (int y = y0; y <= y1; ++y) {
    const float fy = static_cast<float>(y);
    float xl = 1e30f, xr = -1e30f;
    for (int i = 0; i < count; ++i) {
      const int j = (i + 1) % count;
      const float ya = sy[i], yb = sy[j];
      if ((fy < std::min(ya, yb) - 1e-4f) || (fy > std::max(ya, yb) + 1e-4f)) continue;
      float x;
      if (std::abs(yb - ya) < 1e-6f) {
        xl = std::min(xl, std::min(sx[i], sx[j]));
        xr = std::max(xr, std::max(sx[i], sx[j]));
        continue;
      }
      x = sx[i] + (fy - ya) * (sx[j] - sx[i]) / (yb - ya);
      xl = std::min(xl, x);
      xr = std::max(xr, x);
    }
    const int x0 = std::max(0, static_cast<int>(std::ceil(xl - 1e-4f)));
    const int x1 = std::min(t.W - 1, static_cast<int>(std::floor(xr + 1e-4f)));
    if (x0 <= x1) span(y, x0, x1, A, B, C);
  }
  return true;
}

// Depth-tested fill of ids.
inline void drawTriangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c, std::int32_t id,
                         RasterTarget& t) {
  rasterizeTriangle(a, b, c, t, [&](int y, int x0, int x1, float A, float B, float C) {
    float* zr = t.invz.data() + static_cast<std::size_t>(y) * t.W;
    std::int32_t* ir = t.id.data() + static_cast<std::size_t>(y) * t.W;
    const float base = B * y + C;
    for (int x = x0; x <= x1; ++x) {
      const float iz = A * x + base;
      if (iz > zr[x]) {
        zr[x] = iz;
        ir[x] = id;
      }
    }
  });
}

}  // namespace beslam::sim::detail
