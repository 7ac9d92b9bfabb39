// Triangle meshes for the shape prior: exact point-to-mesh distance, inside tests that survive open
// meshes, area-weighted surface samples, Chamfer distance and PLY files.
//
// Contract
// - Mesh: vertices (metres) and faces as index triples, counter-clockwise seen from outside.
// - MeshDistance::signedDistance: exact distance to the nearest triangle, negative inside. Inside means a
//   generalised winding number above 0.5, so overlapping closed parts (wheels in the body) and small
//   holes (the synthetic cars' missing cabin floor) still give the right sign. The faces must face
//   outwards; orientOutward makes them so per connected part.
// - orientOutward: splits the mesh into parts (faces joined by edges, vertices welded by position),
//   makes the faces of each part agree across their shared edges, then turns a part whose signed volume
//   about its own centroid is negative; returns the number of faces reversed. The synthetic cars need it:
//   their faces follow the renderer (bodies wind inwards, one side's wheel rims against its caps).
// - surfaceSamples: n points drawn area-weighted with the given seed (same seed, same points);
//   exterior_only drops points on faces buried inside the mesh (their outside neighbour is inside).
// - chamferDistance(estimate, truth, n, seed): the symmetric mean surface distance, metres: (mean over n
//   samples of estimate of the distance to truth + mean over n exterior samples of truth of the distance
//   to estimate) / 2. Exact point-to-triangle distances; infinity when either mesh has no area.
// - PLY files: beslam::formats::writePlyMesh / readPlyMesh (beslam/formats/ply.hpp); Mesh is that
//   TriangleMesh.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "beslam/formats/ply.hpp"

namespace beslam::recon::shape {

using Mesh = formats::TriangleMesh;

class MeshDistance {
 public:
  explicit MeshDistance(const Mesh& mesh);
  double unsignedDistance(const Eigen::Vector3d& p) const;
  double windingNumber(const Eigen::Vector3d& p) const;
  double signedDistance(const Eigen::Vector3d& p) const;
  // The same, but inside the distance is to the EXTERIOR surface: faces buried inside other parts (the
  // body's top under the cabin, wheel rims inside the body) do not count. The nearest of the four
  // nearest triangles whose closest point is exterior, else the nearest of `samples` exterior surface
  // samples (made once, on first use; spacing about sqrt(area / samples)).
  double solidSignedDistance(const Eigen::Vector3d& p, int samples = 6000) const;
  // First hit of the segment from -> to (excluding its last `slack` metres); false when there is none.
  bool segmentHits(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double slack = 0.01) const;
  // Distance along the unit direction to the first triangle the ray from origin meets; infinity if none.
  double rayHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;

 private:
  std::vector<Eigen::Vector3d> a_, b_, c_;
  Mesh mesh_;
  mutable std::vector<Eigen::Vector3d> exterior_;
};

// Closest point on triangle (a, b, c) to p.
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c);

int orientOutward(Mesh& mesh);

std::vector<Eigen::Vector3d> surfaceSamples(const Mesh& mesh, int n, std::uint64_t seed, bool exterior_only = false);

double chamferDistance(const Mesh& estimate, const Mesh& truth, int n, std::uint64_t seed);

// Deterministic uniform numbers in [0, 1) (the same on every platform; std:: distributions are not).
class Random {
 public:
  explicit Random(std::uint64_t seed);
  double uniform();
  double uniform(double a, double b) { return a + (b - a) * uniform(); }

 private:
  std::uint64_t state_;
};

}  // namespace beslam::recon::shape
