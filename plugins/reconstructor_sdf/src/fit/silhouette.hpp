// The silhouette term of Algorithm 2: how far a camera ray passes from the shape prior's surface.
//
// Contract
// - leastLevel(prior, origin, direction, size, code, &t): object frame, metres, direction unit length.
//   Returns the least of the prior's level (ShapePrior::levelSized: normalised, continuous, the sign and
//   zero set of the distance) along the ray for t >= 0, and t there (t may be null): > 0 the ray misses
//   the shape, < 0 it passes inside. The metric distance is not searched: it divides by a gradient that
//   jumps between grid cells, and its least value would sit on a cell boundary. The search runs over the
//   stretch of the ray within the sphere round the box [-size/2, size/2], grown by kSearchMargin (steps of
//   half the level times the smallest side, kMinStep to kMaxStep, then a golden-section refinement around
//   the least sample); a ray that passes that sphere returns the level at its point nearest the box
//   centre. Where the level has two valleys along the ray within a step of each other in value, the one
//   found may be the higher (a few per cent). Never NaN for finite input.
// - silhouetteLevel(...) is the least level as a differentiable T (double or ceres::Jet). At a smooth least
//   point the level's t-derivative is 0, so (envelope theorem) the level at that fixed t has the
//   derivative of the least level with respect to pose, code and size. The level is trilinear per grid
//   cell and the least point often sits on a cell face, a kink: there t is that face's crossing, itself
//   differentiable, so the derivative stays that of the least level.
// - silhouetteViolation(..., inside): how far the ray is on the wrong side, in level units, as a T: for a
//   mask ray (inside) the least level if above 0, for a background ray minus the least level if below 0,
//   else 0. Its searches stop as soon as the answer is known to be 0 (Search above), at a fraction of the
//   cost; the values are silhouetteLevel's but for a background ray whose samples all stay above 0 while
//   the refinement between two of them dips below (a graze of millimetres): 0 here.
// - metresPerLevel(...): the metric distance over the level at the closest approach (where the level is
//   near 0, the cube root of the box's volume): a residual scales the level by it once, at the start of a
//   solve, so its unit is about a metre and its derivative stays exact. least_level (may be null): the
//   least level it searched, leastLevel's value.
// - A ray through a pixel of the car's mask should meet the car (level <= 0); a ray through a background
//   pixel beside it should pass it (level >= 0). object_fit.hpp turns the violations into residuals.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>

#include "shape/shape_prior.hpp"

namespace beslam::recon::fit {

// What a search must find: the least level (Least), or only whether the ray meets the shape: UntilInside
// stops at the first sample at or below 0 and returns it (a mask ray that meets the car needs no more);
// OnlyInside refines only when a sample is at or below 0, else returns the least sample, which is then
// above 0 (a background ray that passes the car needs no more). The step rule is meant not to step over
// the surface, so the sign of what they return is that of the least level but for grazes of millimetres.
enum class Search { Least, UntilInside, OnlyInside };

constexpr double kSearchMargin = 0.5;  // m beyond the box's bounding sphere the closest approach is searched
constexpr double kMinStep = 0.05;      // m, smallest search step (about half a cell of the prior's grid)
constexpr double kMaxStep = 0.10;      // m, largest (under the prior's grid cell, so no cell is skipped)

template <typename T>
double leastLevel(const shape::ShapePrior& prior, const T origin[3], const T direction[3], const T size[3],
                  const T* code, double* t_out, Search search = Search::Least) {
  using shape::scalarPart;
  constexpr int kMaxDims = 16;
  const int K = std::min(prior.dimensions(), kMaxDims);  // fitObject allows at most kMaxFitDims (10)
  double o[3], u[3], s[3], z[kMaxDims];
  for (int a = 0; a < 3; ++a) o[a] = scalarPart(origin[a]), u[a] = scalarPart(direction[a]), s[a] = scalarPart(size[a]);
  for (int k = 0; k < K; ++k) z[k] = scalarPart(code[k]);
  const auto dist = [&](double t) {
    const double p[3] = {o[0] + t * u[0], o[1] + t * u[1], o[2] + t * u[2]};
    return prior.levelSized<double>(p, s, z);
  };
  // The ray's stretch within the sphere around the box grown by kSearchMargin, from t >= 0.
  const double radius = 0.5 * std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) + kSearchMargin;
  const double t_centre = -(o[0] * u[0] + o[1] * u[1] + o[2] * u[2]);
  const double miss2 = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - t_centre * t_centre;
  const double half = std::sqrt(std::max(0.0, radius * radius - miss2));
  const double t0 = std::max(0.0, t_centre - half), t1 = t_centre + half;
  if (!(miss2 < radius * radius && t1 > t0)) {  // passes the sphere: the point nearest the centre
    const double t = std::max(0.0, t_centre);
    if (t_out) *t_out = t;
    return dist(t);
  }
  // Samples along the stretch; the least one and its neighbours bracket the minimum. The level changes by
  // at most |dp| / (smallest side) per step dp, so a step of half the level times that side cannot cross
  // the surface.
  const double min_side = std::min({s[0], s[1], s[2]});
  constexpr int kMaxSamples = 256;
  double ts[kMaxSamples], ds[kMaxSamples];
  int n = 0, best_i = 0;
  for (double t = t0;;) {
    ts[n] = t, ds[n] = dist(t);
    if (ds[n] < ds[best_i]) best_i = n;
    if (search == Search::UntilInside && ds[n] <= 0) {
      if (t_out) *t_out = t;
      return ds[n];
    }
    if (++n == kMaxSamples || t >= t1) break;
    t = std::min(t1, t + std::clamp(0.5 * std::abs(ds[n - 1]) * min_side, kMinStep, kMaxStep));
  }
  double best = ds[best_i], best_t = ts[best_i];
  if (search == Search::OnlyInside && best > 0) {
    if (t_out) *t_out = best_t;
    return best;
  }
  const double lo = ts[std::max(best_i - 1, 0)], hi = ts[std::min(best_i + 1, n - 1)];
  // Golden-section refinement in [lo, hi] (the least sample and its neighbours).
  constexpr double g = 0.6180339887498949;
  double a = lo, b = hi;
  double c = b - g * (b - a), e = a + g * (b - a), dc = dist(c), de = dist(e);
  for (int i = 0; i < 16 && b - a > 1e-4; ++i) {
    if (dc < de) {
      b = e, e = c, de = dc, c = b - g * (b - a), dc = dist(c);
    } else {
      a = c, c = e, dc = de, e = a + g * (b - a), de = dist(e);
    }
  }
  const double tc = dc < de ? c : e, dm = std::min(dc, de);
  if (dm < best) best = dm, best_t = tc;
  if (t_out) *t_out = best_t;
  return best;
}

// The level at a least point t along the ray as a differentiable T (silhouetteLevel below).
template <typename T>
T levelAtLeast(const shape::ShapePrior& prior, const T origin[3], const T direction[3], const T size[3], const T* code,
               double t) {
  using shape::scalarPart;
  // The level is trilinear per grid cell, so along the ray it has a kink at every cell face; its least
  // value often sits on one. There the t-derivative is not 0 and the least point moves with the face:
  // take t where the ray crosses that face (q_a = p_a / s_a on a grid plane), a function of the ray and
  // the size, so the derivative stays exact.
  double o[3], u[3], s[3];
  for (int a = 0; a < 3; ++a) o[a] = scalarPart(origin[a]), u[a] = scalarPart(direction[a]), s[a] = scalarPart(size[a]);
  T t_min = T(t);
  const Eigen::Vector3d lo = prior.gridLo(), hi = prior.gridHi();
  const std::array<int, 3> n = prior.gridSize();
  double nearest = 2e-4;  // m: the golden-section search ends within 1e-4 m of the least point
  for (int a = 0; a < 3; ++a) {
    if (std::abs(u[a]) < 1e-9) continue;
    const double cell = (hi[a] - lo[a]) / (n[a] - 1), q = (o[a] + t * u[a]) / s[a];
    const double plane = lo[a] + std::round((q - lo[a]) / cell) * cell;
    if (plane < lo[a] - 1e-9 || plane > hi[a] + 1e-9) continue;
    const double t_face = (plane * s[a] - o[a]) / u[a];
    if (std::abs(t_face - t) < nearest) {
      nearest = std::abs(t_face - t);
      t_min = (plane * size[a] - origin[a]) / direction[a];
    }
  }
  const T p[3] = {origin[0] + t_min * direction[0], origin[1] + t_min * direction[1], origin[2] + t_min * direction[2]};
  return prior.levelSized(p, size, code);
}

template <typename T>
T silhouetteLevel(const shape::ShapePrior& prior, const T origin[3], const T direction[3], const T size[3],
                  const T* code) {
  double t = 0;
  leastLevel(prior, origin, direction, size, code, &t);
  return levelAtLeast(prior, origin, direction, size, code, t);
}

template <typename T>
T silhouetteViolation(const shape::ShapePrior& prior, const T origin[3], const T direction[3], const T size[3],
                      const T* code, bool inside) {
  double t = 0;
  const double level =
      leastLevel(prior, origin, direction, size, code, &t, inside ? Search::UntilInside : Search::OnlyInside);
  if (inside ? level <= 0 : level >= 0) return T(0.0);
  const T at = levelAtLeast(prior, origin, direction, size, code, t);
  return inside ? at : -at;
}

inline double metresPerLevel(const shape::ShapePrior& prior, const double origin[3], const double direction[3],
                             const double size[3], const double* code, double* least_level = nullptr) {
  double t = 0;
  const double level = leastLevel(prior, origin, direction, size, code, &t);
  if (least_level) *least_level = level;
  const double p[3] = {origin[0] + t * direction[0], origin[1] + t * direction[1], origin[2] + t * direction[2]};
  const double d = prior.distanceSized<double>(p, size, code);
  if (std::abs(level) > 1e-3 && d / level > 0) return d / level;
  return std::cbrt(size[0] * size[1] * size[2]);
}

}  // namespace beslam::recon::fit
