// Triangle meshes as PLY files (object meshes of a run: objects/object_TTTT.ply, map.ply).
// Writer: binary little-endian (float x y z; faces as a uchar count 3 and three int32 indices), written
// atomically, vertices mapped by T (object frame -> world, identity by default). Reader: that layout and
// ASCII PLY whose vertices start with x y z (further vertex properties, e.g. colours, are skipped in
// ASCII); faces must be triangles. Errors throw beslam::Error naming the file (not PLY, truncated, a face
// that is not a triangle, an index past the vertices). SurfaceSampler: area-weighted points on a mesh.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <string>
#include <vector>

namespace beslam::formats {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;  // metres
  std::vector<std::array<int, 3>> faces;  // vertex indices, counter-clockwise seen from outside
};

void writePlyMesh(const std::string& path, const TriangleMesh& mesh,
                  const Eigen::Isometry3d& T = Eigen::Isometry3d::Identity(),
                  const std::string& comment = "BE-SLAM mesh, metres");
TriangleMesh readPlyMesh(const std::string& path);

// Area-weighted points on a mesh's surface, from the caller's own random numbers (each caller keeps its
// generator and stream): face(r) is the face holding running area r in [0, totalArea()); point(face, u, v)
// the point of that face for u, v in [0, 1) (a pair past the diagonal folded back into the triangle).
// The mesh must outlive the sampler.
class SurfaceSampler {
 public:
  explicit SurfaceSampler(const TriangleMesh& mesh) : mesh_(mesh) {
    double total = 0;
    for (const auto& f : mesh.faces) {
      const Eigen::Vector3d& p0 = mesh.vertices[f[0]];
      total += 0.5 * (mesh.vertices[f[1]] - p0).cross(mesh.vertices[f[2]] - p0).norm();
      cumulative_.push_back(total);
    }
  }
  double totalArea() const { return cumulative_.empty() ? 0 : cumulative_.back(); }
  size_t face(double r) const {
    const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), r);
    return std::min(cumulative_.size() - 1, static_cast<size_t>(it - cumulative_.begin()));
  }
  Eigen::Vector3d point(size_t face, double u, double v) const {
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const auto& f = mesh_.faces[face];
    const Eigen::Vector3d& p0 = mesh_.vertices[f[0]];
    return p0 + u * (mesh_.vertices[f[1]] - p0) + v * (mesh_.vertices[f[2]] - p0);
  }

 private:
  const TriangleMesh& mesh_;
  std::vector<double> cumulative_;
};

}  // namespace beslam::formats
