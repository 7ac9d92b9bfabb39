#include "objects/surface_index.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>

namespace beslam::orb::objects {

uint64_t SurfaceIndex::key(int64_t x, int64_t y, int64_t z) {
  // 21 bits per axis (cells of a car-sized object never come near the limit).
  const uint64_t m = (1u << 21) - 1;
  return (static_cast<uint64_t>(x) & m) | ((static_cast<uint64_t>(y) & m) << 21) |
         ((static_cast<uint64_t>(z) & m) << 42);
}

SurfaceIndex::SurfaceIndex(const std::vector<Eigen::Vector3d>& points, double radius)
    : points_(points), radius_(radius) {
  if (!(radius > 0)) throw std::invalid_argument("SurfaceIndex: radius must be > 0");
  inv_cell_ = 1.0 / radius;
  for (size_t i = 0; i < points_.size(); ++i) {
    if (!points_[i].allFinite() || points_[i].cwiseAbs().maxCoeff() * inv_cell_ > 1e6)
      throw std::invalid_argument("SurfaceIndex: a surface sample is not finite or too far out");
    const Eigen::Vector3d c = (points_[i] * inv_cell_).array().floor();
    cells_[key(static_cast<int64_t>(c.x()), static_cast<int64_t>(c.y()), static_cast<int64_t>(c.z()))].push_back(
        static_cast<uint32_t>(i));
  }
  normals_.assign(points_.size(), Eigen::Vector3d::Zero());
  const double r2 = 0.25 * radius_ * radius_;
  for (size_t i = 0; i < points_.size(); ++i) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
    int n = 0;
    forEachNear(points_[i], [&](uint32_t j) {
      const Eigen::Vector3d d = points_[j] - points_[i];
      if (d.squaredNorm() > r2) return;
      mean += d;
      second += d * d.transpose();
      ++n;
    });
    if (n < 3) continue;
    mean /= n;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(second / n - mean * mean.transpose());
    const Eigen::Vector3d ev = eig.eigenvalues();  // increasing
    if (ev(1) <= 1e-6 * ev(2)) continue;           // on a line: no plane
    normals_[i] = eig.eigenvectors().col(0).normalized();
  }
}

void SurfaceIndex::forEachNear(const Eigen::Vector3d& q, const std::function<void(uint32_t)>& f) const {
  const Eigen::Vector3d c = (q * inv_cell_).array().floor();
  const int64_t cx = static_cast<int64_t>(c.x()), cy = static_cast<int64_t>(c.y()), cz = static_cast<int64_t>(c.z());
  for (int64_t dx = -1; dx <= 1; ++dx)
    for (int64_t dy = -1; dy <= 1; ++dy)
      for (int64_t dz = -1; dz <= 1; ++dz) {
        auto it = cells_.find(key(cx + dx, cy + dy, cz + dz));
        if (it == cells_.end()) continue;
        for (uint32_t i : it->second) f(i);
      }
}

std::optional<size_t> SurfaceIndex::nearest(const Eigen::Vector3d& q) const {
  if (points_.empty() || !q.allFinite()) return std::nullopt;
  if ((q * inv_cell_).cwiseAbs().maxCoeff() > 1e6) return std::nullopt;
  double best = radius_ * radius_;
  std::optional<size_t> found;
  forEachNear(q, [&](uint32_t i) {
    const double d = (points_[i] - q).squaredNorm();
    if (d < best || (d == best && found && i < *found)) {
      best = d;
      found = i;
    }
  });
  return found;
}

}  // namespace beslam::orb::objects
