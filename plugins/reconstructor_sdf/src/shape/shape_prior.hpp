// ShapePrior: a linear (PCA) shape space of cars as signed-distance grids, learnt from the project's own
// procedural cars (docs/reconstruction.md).
//
// Contract
// - Object frame = the landmark frame of interfaces/include/beslam/data.h: x forward, y left, z up,
//   origin at the centre of the box, metres. A car of box size s = (l, w, h) lives in [-s/2, s/2].
// - Shape is separate from size: the grids hold the signed distance phi(q) of a car scaled into the unit
//   box, at normalised points q = p / s (per axis) on a regular grid over [lo, hi] (the unit box plus a
//   margin). phi(q; z) = mean(q) + sum_k z_k basis_k(q), trilinear between grid nodes; the basis is
//   orthonormal over the nodes and z_k has standard deviation codeStd()[k] over the training cars, so
//   the regulariser of a fit is |z / codeStd|^2 (standard deviations).
// - distance(p, s, z) is in METRES: phi / |grad_p phi| with grad_p phi = grad_q phi / s, the distance to
//   the local tangent plane of the zero set after the anisotropic scaling. It is exact for planar faces
//   and the zero set is exact for any s; elsewhere it is a first-order approximation. Points outside the
//   grid get the value at the nearest grid point plus their metric distance to it. Never NaN for finite
//   input and positive size; templated so ceres::Jet works (Ceres AutoDiff).
// - mesh(z, s): the zero set by marching tetrahedra on the grid, object frame, metres, welded vertices,
//   faces counter-clockwise seen from outside (normals point to positive distance).
// - surfaceSamples(z, s, n): n points on that mesh, area-weighted, deterministic.
// - File (.bsdf): binary, little-endian, versioned, magic, FNV-1a checksum, written atomically by save().
//   load() throws one beslam::Error naming the file and the problem (missing, not a prior, wrong
//   version, truncated, damaged).
// - Training (trainShapePrior): deterministic; same shapes and options give a byte-identical file.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "shape/mesh.hpp"

namespace beslam::recon::shape {

// The scalar part of a double or a ceres::Jet (without including Ceres).
template <typename T>
inline double scalarPart(const T& x) {
  if constexpr (std::is_arithmetic_v<T>)
    return static_cast<double>(x);
  else
    return x.a;
}

// One training car: its mesh in the object frame (metres) and its box size (l, w, h).
struct TrainingShape {
  Mesh mesh;
  Eigen::Vector3d size;
};

struct TrainOptions {
  std::array<int, 3> grid = {44, 22, 22};  // nodes along x, y, z
  double margin = 0.15;                    // grid reaches the unit box +- margin (normalised units)
  int dims = 0;                            // basis size; 0: the fewest reaching min_explained (at most max_dims)
  double min_explained = 0.99;
  int max_dims = 8;
  std::uint64_t seed = 0;  // recorded in the file (the caller draws the shapes from it)
};

class ShapePrior {
 public:
  static constexpr std::uint32_t kVersion = 1;

  static ShapePrior load(const std::string& path);
  void save(const std::string& path) const;
  std::string serialise() const;  // the file's bytes

  int dimensions() const { return dims_; }
  const Eigen::VectorXd& codeStd() const { return std_; }
  const Eigen::VectorXd& explainedVariance() const { return explained_; }  // fraction per dimension
  std::array<int, 3> gridSize() const { return {n_[0], n_[1], n_[2]}; }
  Eigen::Vector3d gridLo() const { return {lo_[0], lo_[1], lo_[2]}; }
  Eigen::Vector3d gridHi() const { return {hi_[0], hi_[1], hi_[2]}; }
  int trainingShapes() const { return training_shapes_; }
  std::uint64_t seed() const { return seed_; }

  // Signed distance (metres, negative inside) of p_obj for a box of size `size` and code (dimensions()
  // values; nullptr = the mean shape).
  template <typename T>
  T distance(const T p_obj[3], const Eigen::Vector3d& size, const T* code) const {
    const T s[3] = {T(size.x()), T(size.y()), T(size.z())};
    return distanceSized(p_obj, s, code);
  }
  // The same with the size as a variable (size refinement).
  template <typename T>
  T distanceSized(const T p_obj[3], const T size[3], const T* code) const {
    return field(p_obj, size, code, true);
  }
  // The normalised level phi (trilinear, outside the grid plus the normalised distance to it): same sign
  // and zero set as distanceSized and continuous everywhere, but not in metres. The metric distance
  // divides by a gradient that jumps between grid cells; searches along a ray use this instead.
  template <typename T>
  T levelSized(const T p_obj[3], const T size[3], const T* code) const {
    return field(p_obj, size, code, false);
  }

  double distance(const Eigen::Vector3d& p_obj, const Eigen::Vector3d& size, const Eigen::VectorXd& code) const {
    const double p[3] = {p_obj.x(), p_obj.y(), p_obj.z()};
    return distance<double>(p, size, code.size() ? code.data() : nullptr);
  }

  // Normalised phi at grid node (i, j, k) for a code.
  double nodeValue(int i, int j, int k, const Eigen::VectorXd& code) const;
  // Least-squares code of a normalised grid (the projection onto the basis).
  Eigen::VectorXd project(const std::vector<double>& grid_values) const;

  Mesh mesh(const Eigen::VectorXd& code, const Eigen::Vector3d& size) const;
  std::vector<Eigen::Vector3d> surfaceSamples(const Eigen::VectorXd& code, const Eigen::Vector3d& size, int n,
                                              std::uint64_t seed = kSurfaceSampleSeed) const;
  static constexpr std::uint64_t kSurfaceSampleSeed = 1;  // the default seed of surfaceSamples

  // Normalised signed-distance grid of a training mesh (node order: x fastest, then y, then z).
  std::vector<double> sampleGrid(const TrainingShape& shape) const;

  friend ShapePrior trainShapePrior(const std::vector<TrainingShape>& shapes, const TrainOptions& options);

 private:
  int n_[3] = {0, 0, 0};
  double lo_[3] = {0, 0, 0}, hi_[3] = {0, 0, 0}, cell_[3] = {1, 1, 1};
  int dims_ = 0;
  int training_shapes_ = 0;
  std::uint64_t seed_ = 0;
  Eigen::VectorXd std_, explained_;
  std::vector<float> values_;  // per node: mean, basis_1 .. basis_K (node-major)

  void setGrid(const std::array<int, 3>& n, double margin);
  template <typename T>
  T field(const T p_obj[3], const T size[3], const T* code, bool metric) const;
  std::size_t node(int i, int j, int k) const { return (static_cast<std::size_t>(k) * n_[1] + j) * n_[0] + i; }
};

// PCA of the shapes' normalised grids. Throws beslam::Error for fewer than 2 shapes or a bad grid.
ShapePrior trainShapePrior(const std::vector<TrainingShape>& shapes, const TrainOptions& options);

template <typename T>
T ShapePrior::field(const T p_obj[3], const T size[3], const T* code, bool metric) const {
  using std::sqrt;
  T q[3], qc[3];
  bool outside = false;
  for (int a = 0; a < 3; ++a) {
    q[a] = p_obj[a] / size[a];
    const double qs = scalarPart(q[a]);
    if (!(qs >= lo_[a])) {  // also catches NaN
      qc[a] = T(lo_[a]);
      outside = true;
    } else if (qs > hi_[a]) {
      qc[a] = T(hi_[a]);
      outside = true;
    } else {
      qc[a] = q[a];
    }
  }
  int c0[3];
  T f[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (scalarPart(qc[a]) - lo_[a]) / cell_[a];
    c0[a] = std::clamp(static_cast<int>(std::floor(u)), 0, n_[a] - 2);
    f[a] = (qc[a] - T(lo_[a] + c0[a] * cell_[a])) / cell_[a];
  }
  const int stride = dims_ + 1;
  T v[8];
  for (int c = 0; c < 8; ++c) {
    const float* g = &values_[node(c0[0] + (c & 1), c0[1] + ((c >> 1) & 1), c0[2] + ((c >> 2) & 1)) * stride];
    T s = T(static_cast<double>(g[0]));
    if (code)
      for (int k = 0; k < dims_; ++k) s += code[k] * static_cast<double>(g[k + 1]);
    v[c] = s;
  }
  const T one(1.0);
  const T gx[2] = {one - f[0], f[0]}, gy[2] = {one - f[1], f[1]}, gz[2] = {one - f[2], f[2]};
  T phi(0.0), dx(0.0), dy(0.0), dz(0.0);
  for (int c = 0; c < 8; ++c) {
    const int ix = c & 1, iy = (c >> 1) & 1, iz = (c >> 2) & 1;
    phi += v[c] * gx[ix] * gy[iy] * gz[iz];
    const double sx = ix ? 1.0 : -1.0, sy = iy ? 1.0 : -1.0, sz = iz ? 1.0 : -1.0;
    dx += v[c] * sx * gy[iy] * gz[iz];
    dy += v[c] * gx[ix] * sy * gz[iz];
    dz += v[c] * gx[ix] * gy[iy] * sz;
  }
  if (!metric) {
    if (outside) {
      T o2(0.0);
      for (int a = 0; a < 3; ++a) o2 += (q[a] - qc[a]) * (q[a] - qc[a]);
      if (scalarPart(o2) > 0) phi += sqrt(o2);
    }
    return phi;
  }
  // Gradient in metres: d phi / d p = (d phi / d q) / s.
  const T Gx = dx / (cell_[0] * size[0]), Gy = dy / (cell_[1] * size[1]), Gz = dz / (cell_[2] * size[2]);
  const T g2 = Gx * Gx + Gy * Gy + Gz * Gz;
  // Outside, the gradient is floored at half the smallest an exact normalised SDF can have (1 / longest
  // side). Inside, near the medial surfaces the gradient vanishes and jumps between cells, so it is
  // floored at 1 / cbrt(l w h): the interior stays monotone (no false minima for points pushed inside),
  // exact near the sides, top and bottom, and up to l / cbrt(l w h) (about 2) too shallow inside the
  // front and rear faces.
  T g_min;
  if (scalarPart(phi) >= 0) {
    int longest = 0;
    for (int a = 1; a < 3; ++a)
      if (scalarPart(size[a]) > scalarPart(size[longest])) longest = a;
    g_min = 0.5 / size[longest];
  } else {
    using std::cbrt;
    g_min = 1.0 / cbrt(size[0] * size[1] * size[2]);
  }
  T d = scalarPart(g2) > scalarPart(g_min * g_min) ? phi / sqrt(g2) : phi / g_min;
  if (outside) {
    T o2(0.0);
    for (int a = 0; a < 3; ++a) {
      const T e = (q[a] - qc[a]) * size[a];
      o2 += e * e;
    }
    if (scalarPart(o2) > 0) d += sqrt(o2);
  }
  return d;
}

}  // namespace beslam::recon::shape
