#include "shape/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <ostream>
#include <sstream>

#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"

namespace beslam::recon::shape {

Random::Random(std::uint64_t seed) : state_(seed ^ 0x9e3779b97f4a7c15ull) {}

double Random::uniform() {  // splitmix64, top 53 bits
  std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
}

Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  // Regions of the triangle's plane: three vertices, three edges, the face (barycentric tests).
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double sum = va + vb + vc;
  if (!(std::abs(sum) > 0)) return a;  // degenerate triangle
  return a + ab * (vb / sum) + ac * (vc / sum);
}

MeshDistance::MeshDistance(const Mesh& mesh) : mesh_(mesh) {
  for (const auto& f : mesh.faces) {
    a_.push_back(mesh.vertices[f[0]]);
    b_.push_back(mesh.vertices[f[1]]);
    c_.push_back(mesh.vertices[f[2]]);
  }
}

double MeshDistance::unsignedDistance(const Eigen::Vector3d& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < a_.size(); ++i)
    best = std::min(best, (closestPointOnTriangle(p, a_[i], b_[i], c_[i]) - p).squaredNorm());
  return std::sqrt(best);
}

double MeshDistance::windingNumber(const Eigen::Vector3d& p) const {
  // Sum of the signed solid angles of the triangles seen from p (Van Oosterom and Strackee), over 4 pi.
  double sum = 0;
  for (size_t i = 0; i < a_.size(); ++i) {
    const Eigen::Vector3d a = a_[i] - p, b = b_[i] - p, c = c_[i] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    sum += 2 * std::atan2(num, den);
  }
  return sum / (4 * M_PI);
}

double MeshDistance::solidSignedDistance(const Eigen::Vector3d& p, int samples) const {
  if (windingNumber(p) <= 0.5) return unsignedDistance(p);
  std::vector<std::pair<double, size_t>> near(a_.size());
  for (size_t i = 0; i < a_.size(); ++i)
    near[i] = {(closestPointOnTriangle(p, a_[i], b_[i], c_[i]) - p).squaredNorm(), i};
  const size_t k = std::min<size_t>(4, near.size());
  std::partial_sort(near.begin(), near.begin() + k, near.end());
  for (size_t j = 0; j < k; ++j) {
    const size_t i = near[j].second;
    const Eigen::Vector3d c = closestPointOnTriangle(p, a_[i], b_[i], c_[i]);
    const Eigen::Vector3d n = (b_[i] - a_[i]).cross(c_[i] - a_[i]).normalized();
    if (windingNumber(c + 1e-3 * n) <= 0.5) return -std::sqrt(near[j].first);
  }
  if (exterior_.empty()) exterior_ = surfaceSamples(mesh_, samples, 7, true);
  double best = std::numeric_limits<double>::infinity();
  for (const auto& s : exterior_) best = std::min(best, (s - p).squaredNorm());
  return -std::sqrt(best);
}

double MeshDistance::rayHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& u) const {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < a_.size(); ++i) {  // Moller-Trumbore, both sides
    const Eigen::Vector3d e1 = b_[i] - a_[i], e2 = c_[i] - a_[i];
    const Eigen::Vector3d h = u.cross(e2);
    const double det = e1.dot(h);
    if (std::abs(det) < 1e-12) continue;
    const Eigen::Vector3d s = origin - a_[i];
    const double bu = s.dot(h) / det;
    if (bu < 0 || bu > 1) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double bv = u.dot(q) / det;
    if (bv < 0 || bu + bv > 1) continue;
    const double t = e2.dot(q) / det;
    if (t > 1e-9) best = std::min(best, t);
  }
  return best;
}

bool MeshDistance::segmentHits(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double slack) const {
  const double len = (to - from).norm();
  if (!(len > slack)) return false;
  return rayHit(from, (to - from) / len) < len - slack;
}

double MeshDistance::signedDistance(const Eigen::Vector3d& p) const {
  const double d = unsignedDistance(p);
  return windingNumber(p) > 0.5 ? -d : d;
}

int orientOutward(Mesh& mesh) {
  // Weld vertices by position, then walk each part across shared edges, turning every face to agree with
  // the face it was reached from (neighbours traverse a shared edge in opposite directions).
  const int nf = static_cast<int>(mesh.faces.size());
  std::map<std::array<double, 3>, int> weld;
  std::vector<std::array<int, 3>> f(nf);
  for (int i = 0; i < nf; ++i)
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d& p = mesh.vertices[mesh.faces[i][c]];
      f[i][c] = weld.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, static_cast<int>(weld.size())).first->second;
    }
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  for (int i = 0; i < nf; ++i)
    for (int c = 0; c < 3; ++c) edge_faces[std::minmax(f[i][c], f[i][(c + 1) % 3])].push_back(i);
  auto hasDirected = [&](int face, int a, int b) {
    for (int c = 0; c < 3; ++c)
      if (f[face][c] == a && f[face][(c + 1) % 3] == b) return true;
    return false;
  };
  std::vector<int> part(nf, -1);
  std::vector<bool> flip(nf, false);
  std::vector<double> volume;
  int parts = 0;
  for (int seed = 0; seed < nf; ++seed) {
    if (part[seed] >= 0) continue;
    std::vector<int> members{seed}, stack{seed};
    part[seed] = parts;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      for (int c = 0; c < 3; ++c) {
        int a = f[i][c], b = f[i][(c + 1) % 3];
        if (flip[i]) std::swap(a, b);  // the edge as face i runs it after its flip
        for (int j : edge_faces[std::minmax(a, b)]) {
          if (part[j] >= 0) continue;
          part[j] = parts;
          flip[j] = hasDirected(j, a, b);  // same direction as i: j must turn
          members.push_back(j);
          stack.push_back(j);
        }
      }
    }
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int i : members)
      for (int v : mesh.faces[i]) centroid += mesh.vertices[v];
    centroid /= 3.0 * members.size();
    double vol = 0;
    for (int i : members) {
      const auto& t = mesh.faces[i];
      const double v =
          (mesh.vertices[t[0]] - centroid).dot((mesh.vertices[t[1]] - centroid).cross(mesh.vertices[t[2]] - centroid)) /
          6;
      vol += flip[i] ? -v : v;
    }
    volume.push_back(vol);
    ++parts;
  }
  int changed = 0;
  for (int i = 0; i < nf; ++i)
    if (flip[i] != (volume[part[i]] < 0)) {
      std::swap(mesh.faces[i][1], mesh.faces[i][2]);
      ++changed;
    }
  return changed;
}

std::vector<Eigen::Vector3d> surfaceSamples(const Mesh& mesh, int n, std::uint64_t seed, bool exterior_only) {
  const formats::SurfaceSampler sampler(mesh);
  std::vector<Eigen::Vector3d> out;
  if (n <= 0 || !(sampler.totalArea() > 0)) return out;
  std::unique_ptr<MeshDistance> inside;
  if (exterior_only) inside = std::make_unique<MeshDistance>(mesh);
  Random rng(seed);
  const int max_tries = 50 * n;
  for (int tries = 0; static_cast<int>(out.size()) < n && tries < max_tries; ++tries) {
    const size_t i = sampler.face(rng.uniform() * sampler.totalArea());
    const double u = rng.uniform(), v = rng.uniform();
    const Eigen::Vector3d p = sampler.point(i, u, v);
    if (inside) {
      const auto& f = mesh.faces[i];
      const Eigen::Vector3d &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
      const Eigen::Vector3d nrm = (b - a).cross(c - a).normalized();
      if (inside->windingNumber(p + 0.01 * nrm) > 0.5) continue;  // a buried face
    }
    out.push_back(p);
  }
  return out;
}

double chamferDistance(const Mesh& a, const Mesh& b, int n, std::uint64_t seed) {
  const MeshDistance da(a), db(b);
  const auto sa = surfaceSamples(a, n, seed, false), sb = surfaceSamples(b, n, seed + 1, true);
  if (sa.empty() || sb.empty()) return std::numeric_limits<double>::infinity();
  double ab = 0, ba = 0;
  for (const auto& p : sa) ab += db.unsignedDistance(p);
  for (const auto& p : sb) ba += da.unsignedDistance(p);
  return 0.5 * (ab / sa.size() + ba / sb.size());
}

}  // namespace beslam::recon::shape
