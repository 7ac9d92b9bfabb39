// Triangle meshes as PLY files (object meshes of a run: objects/object_TTTT.ply, map.ply).
// Writer: binary little-endian (float x y z; faces as a uchar count 3 and three int32 indices), written
// atomically, vertices mapped by T (object frame -> world, identity by default). Reader: that layout and
// ASCII PLY whose vertices start with x y z (further vertex properties, e.g. colours, are skipped in
// ASCII); faces must be triangles. Errors throw beslam::Error naming the file (not PLY, truncated, a face
// that is not a triangle, an index past the vertices).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
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

}  // namespace beslam::formats
