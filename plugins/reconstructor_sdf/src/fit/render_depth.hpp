// Differentiable depth rendering of the shape prior's SDF (the E_rend term of Algorithm 2).
//
// Contract
// - renderDepth(prior, origin, direction, size, code, depth): object frame, metres; direction unit length.
//   Sphere-traces the prior's distance from the origin (steps of 0.9 d, at least 5 mm; a sign change is
//   bisected) up to max_range. On a hit it returns true and depth = the distance along the ray, made
//   differentiable by one Newton step on d(origin + t direction) = 0 from the traced t0:
//     t = t0 - d(origin + t0 direction) / (d/dt d at t0)
//   so a ceres::Jet carries dt/dtheta = -(dd/dtheta) / (dd/dt), the implicit-function derivative. t0 is
//   taken just outside the surface and the slope dd/dt is a one-sided difference outside (the metric
//   distance's slope differs inside and outside, shape_prior.hpp). Grazing rays (dd/dt > -0.05) and
//   misses return false.
// - T is double or ceres::Jet; the code holds prior.dimensions() values (at most kMaxRenderDims).
#pragma once

#include <cmath>

#include "shape/shape_prior.hpp"

namespace beslam::recon::fit {

constexpr int kMaxRenderDims = 16;

template <typename T>
bool renderDepth(const shape::ShapePrior& prior, const T origin[3], const T direction[3], const T size[3],
                 const T* code, T* depth, double max_range = 80.0) {
  using shape::scalarPart;
  const int K = prior.dimensions();
  if (K > kMaxRenderDims) return false;
  double o[3], u[3], s[3], z[kMaxRenderDims];
  for (int a = 0; a < 3; ++a) o[a] = scalarPart(origin[a]), u[a] = scalarPart(direction[a]), s[a] = scalarPart(size[a]);
  for (int k = 0; k < K; ++k) z[k] = scalarPart(code[k]);
  auto dist = [&](double t) {
    const double p[3] = {o[0] + t * u[0], o[1] + t * u[1], o[2] + t * u[2]};
    return prior.distanceSized<double>(p, s, z);
  };
  double t = 0, d = dist(0);
  if (!(d > 0)) return false;  // the camera is inside the object
  bool hit = false;
  for (int i = 0; i < 256 && t < max_range; ++i) {
    const double step = std::max(0.9 * d, 0.005);
    const double t1 = t + step, d1 = dist(t1);
    if (d1 <= 0) {  // crossed: bisect [t, t1]
      double lo = t, hi = t1;
      for (int b = 0; b < 30; ++b) {
        const double mid = 0.5 * (lo + hi);
        (dist(mid) > 0 ? lo : hi) = mid;
      }
      t = lo;  // just outside: the Jet below takes the outside branch of the distance
      hit = true;
      break;
    }
    t = t1, d = d1;
    if (d < 1e-5) {
      hit = true;
      break;
    }
  }
  if (!hit) return false;
  const double h = 1e-4;
  const double slope = (dist(t) - dist(t - h)) / h;  // one-sided, outside (the distance has a kink at 0)
  if (!(slope < -0.05)) return false;                // grazing
  const T p[3] = {origin[0] + t * direction[0], origin[1] + t * direction[1], origin[2] + t * direction[2]};
  *depth = T(t) - prior.distanceSized(p, size, code) / slope;
  return true;
}

}  // namespace beslam::recon::fit
