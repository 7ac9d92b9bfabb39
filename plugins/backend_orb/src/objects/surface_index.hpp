// Nearest surface sample of an object landmark: a voxel hash over points_object (object frame). A query
// looks at the 27 voxels around its own, so with the voxel size equal to the search radius it returns
// the exact nearest sample within that radius (or none). Each sample also gets a surface normal: the
// least-spread direction of the samples within half the radius (zero where fewer than 3 are, or they lie
// on a line).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <unordered_map>
#include <vector>

namespace beslam::orb::objects {

class SurfaceIndex {
 public:
  SurfaceIndex() = default;
  SurfaceIndex(const std::vector<Eigen::Vector3d>& points, double radius);
  // Index of the nearest sample within the radius of q (ties: the lower index), none when there is none.
  std::optional<size_t> nearest(const Eigen::Vector3d& q) const;
  double radius() const { return radius_; }
  bool empty() const { return points_.empty(); }
  const Eigen::Vector3d& point(size_t i) const { return points_[i]; }
  const Eigen::Vector3d& normal(size_t i) const { return normals_[i]; }

 private:
  static uint64_t key(int64_t x, int64_t y, int64_t z);
  void forEachNear(const Eigen::Vector3d& q, const std::function<void(uint32_t)>& f) const;
  std::vector<Eigen::Vector3d> points_, normals_;
  double radius_ = 0, inv_cell_ = 0;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

}  // namespace beslam::orb::objects
