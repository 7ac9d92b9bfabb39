#include "shape/shape_prior.hpp"

#include <Eigen/Eigenvalues>
#include <cstring>
#include <unordered_map>

#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"
#include "shape/checksum.hpp"

namespace beslam::recon::shape {
namespace {

constexpr char kMagic[8] = {'B', 'E', 'S', 'L', 'S', 'D', 'F', 'P'};
constexpr int kMaxNodes = 256;
constexpr int kMaxDims = 64;

template <typename T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

struct Reader {
  const std::string& path;
  const std::string& data;
  size_t at = 0;
  template <typename T>
  T get() {
    if (at + sizeof(T) > data.size())
      throwAt(path, "truncated shape prior (" + std::to_string(data.size()) + " bytes, ends inside the header)");
    T v;
    std::memcpy(&v, data.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
};

}  // namespace

void ShapePrior::setGrid(const std::array<int, 3>& n, double margin) {
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 3 || n[a] > kMaxNodes) throw Error("shape prior: grid size must be 3.." + std::to_string(kMaxNodes));
    n_[a] = n[a];
    lo_[a] = -0.5 - margin;
    hi_[a] = 0.5 + margin;
    cell_[a] = (hi_[a] - lo_[a]) / (n_[a] - 1);
  }
  if (!(margin > 0 && margin < 2)) throw Error("shape prior: grid margin must be in (0, 2)");
}

std::vector<double> ShapePrior::sampleGrid(const TrainingShape& shape) const {
  Mesh unit = shape.mesh;
  for (auto& v : unit.vertices) v = v.cwiseQuotient(shape.size);
  const MeshDistance sdf(unit);
  std::vector<double> out(static_cast<size_t>(n_[0]) * n_[1] * n_[2]);
  for (int k = 0; k < n_[2]; ++k)
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i)
        out[node(i, j, k)] = sdf.solidSignedDistance(
            Eigen::Vector3d(lo_[0] + i * cell_[0], lo_[1] + j * cell_[1], lo_[2] + k * cell_[2]));
  return out;
}

ShapePrior trainShapePrior(const std::vector<TrainingShape>& shapes, const TrainOptions& options) {
  if (shapes.size() < 2) throw Error("shape prior: training needs at least 2 shapes");
  ShapePrior prior;
  prior.setGrid(options.grid, options.margin);
  const int N = static_cast<int>(shapes.size());
  const int G = prior.n_[0] * prior.n_[1] * prior.n_[2];
  Eigen::MatrixXd X(N, G);
  for (int s = 0; s < N; ++s) {
    if (!(shapes[s].size.minCoeff() > 0))
      throw Error("shape prior: training shape " + std::to_string(s) + " has no size");
    const std::vector<double> g = prior.sampleGrid(shapes[s]);
    X.row(s) = Eigen::Map<const Eigen::RowVectorXd>(g.data(), G);
  }
  const Eigen::RowVectorXd mean = X.colwise().mean();
  X.rowwise() -= mean;
  const Eigen::MatrixXd gram = X * X.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
  const Eigen::VectorXd lambda = eig.eigenvalues().reverse().cwiseMax(0.0);
  const Eigen::MatrixXd V = eig.eigenvectors().rowwise().reverse();
  const double total = lambda.sum();
  if (!(total > 0)) throw Error("shape prior: the training shapes are all the same");
  int dims = options.dims;
  const int available = std::max(1, static_cast<int>((lambda.array() > total * 1e-12).count()));
  if (dims <= 0) {
    double acc = 0;
    dims = 0;
    while (dims < std::min(options.max_dims, available) && acc < options.min_explained) acc += lambda(dims++) / total;
  }
  if (dims < 1 || dims > kMaxDims) throw Error("shape prior: dims must be 1.." + std::to_string(kMaxDims));
  dims = std::min(dims, available);
  prior.dims_ = dims;
  prior.training_shapes_ = N;
  prior.seed_ = options.seed;
  prior.std_.resize(dims);
  prior.explained_.resize(dims);
  const int stride = dims + 1;
  prior.values_.assign(static_cast<size_t>(G) * stride, 0.f);
  for (int n = 0; n < G; ++n) prior.values_[static_cast<size_t>(n) * stride] = static_cast<float>(mean(n));
  for (int k = 0; k < dims; ++k) {
    Eigen::VectorXd u = X.transpose() * V.col(k) / std::sqrt(lambda(k));
    Eigen::Index imax = 0;
    u.cwiseAbs().maxCoeff(&imax);
    if (u(imax) < 0) u = -u;  // a fixed sign per direction
    prior.std_(k) = std::sqrt(lambda(k) / (N - 1));
    prior.explained_(k) = lambda(k) / total;
    for (int n = 0; n < G; ++n) prior.values_[static_cast<size_t>(n) * stride + k + 1] = static_cast<float>(u(n));
  }
  return prior;
}

double ShapePrior::nodeValue(int i, int j, int k, const Eigen::VectorXd& code) const {
  const float* g = &values_[node(i, j, k) * (dims_ + 1)];
  double s = g[0];
  for (int d = 0; d < dims_ && d < code.size(); ++d) s += code(d) * g[d + 1];
  return s;
}

Eigen::VectorXd ShapePrior::project(const std::vector<double>& grid_values) const {
  Eigen::VectorXd z = Eigen::VectorXd::Zero(dims_);
  const size_t G = static_cast<size_t>(n_[0]) * n_[1] * n_[2];
  if (grid_values.size() != G) throw Error("shape prior: project needs a grid of the prior's size");
  for (size_t n = 0; n < G; ++n) {
    const float* g = &values_[n * (dims_ + 1)];
    const double r = grid_values[n] - g[0];
    for (int d = 0; d < dims_; ++d) z(d) += r * g[d + 1];
  }
  return z;
}

std::string ShapePrior::serialise() const {
  std::string out(kMagic, sizeof(kMagic));
  put(out, kVersion);
  for (int a = 0; a < 3; ++a) put(out, static_cast<std::uint32_t>(n_[a]));
  put(out, static_cast<std::uint32_t>(dims_));
  put(out, static_cast<std::uint32_t>(training_shapes_));
  put(out, seed_);
  for (int a = 0; a < 3; ++a) put(out, lo_[a]);
  for (int a = 0; a < 3; ++a) put(out, hi_[a]);
  for (int k = 0; k < dims_; ++k) put(out, std_(k));
  for (int k = 0; k < dims_; ++k) put(out, explained_(k));
  out.append(reinterpret_cast<const char*>(values_.data()), values_.size() * sizeof(float));
  put(out, fnv1a(out.data(), out.size()));
  return out;
}

void ShapePrior::save(const std::string& path) const { writeFileAtomic(path, serialise()); }

ShapePrior ShapePrior::load(const std::string& path) {
  const std::string data = readFile(path);
  if (data.size() < sizeof(kMagic) || std::memcmp(data.data(), kMagic, sizeof(kMagic)) != 0)
    throwAt(path, "not a BE-SLAM shape prior (bad magic)");
  Reader r{path, data, sizeof(kMagic)};
  const auto version = r.get<std::uint32_t>();
  if (version != kVersion)
    throwAt(path, "shape prior version " + std::to_string(version) + ", this build reads version " +
                      std::to_string(kVersion));
  ShapePrior p;
  for (int a = 0; a < 3; ++a) {
    const auto n = r.get<std::uint32_t>();
    if (n < 3 || n > static_cast<std::uint32_t>(kMaxNodes)) throwAt(path, "damaged shape prior (grid size)");
    p.n_[a] = static_cast<int>(n);
  }
  const auto dims = r.get<std::uint32_t>();
  if (dims < 1 || dims > static_cast<std::uint32_t>(kMaxDims)) throwAt(path, "damaged shape prior (dimensions)");
  p.dims_ = static_cast<int>(dims);
  p.training_shapes_ = static_cast<int>(r.get<std::uint32_t>());
  p.seed_ = r.get<std::uint64_t>();
  for (int a = 0; a < 3; ++a) p.lo_[a] = r.get<double>();
  for (int a = 0; a < 3; ++a) p.hi_[a] = r.get<double>();
  const size_t G = static_cast<size_t>(p.n_[0]) * p.n_[1] * p.n_[2];
  const size_t expected = r.at + 2 * dims * sizeof(double) + G * (dims + 1) * sizeof(float) + sizeof(std::uint64_t);
  if (data.size() < expected)
    throwAt(path, "truncated shape prior (" + std::to_string(data.size()) + " bytes, expected " +
                      std::to_string(expected) + ")");
  if (data.size() > expected)
    throwAt(path, "damaged shape prior (" + std::to_string(data.size() - expected) + " bytes after the end)");
  std::uint64_t stored;
  std::memcpy(&stored, data.data() + expected - sizeof(stored), sizeof(stored));
  if (stored != fnv1a(data.data(), expected - sizeof(stored))) throwAt(path, "damaged shape prior (checksum mismatch)");
  p.std_.resize(dims);
  p.explained_.resize(dims);
  for (int k = 0; k < p.dims_; ++k) p.std_(k) = r.get<double>();
  for (int k = 0; k < p.dims_; ++k) p.explained_(k) = r.get<double>();
  p.values_.resize(G * (dims + 1));
  std::memcpy(p.values_.data(), data.data() + r.at, p.values_.size() * sizeof(float));
  for (int a = 0; a < 3; ++a) {
    if (!(std::isfinite(p.lo_[a]) && std::isfinite(p.hi_[a]) && p.lo_[a] < p.hi_[a]))
      throwAt(path, "damaged shape prior (grid bounds)");
    p.cell_[a] = (p.hi_[a] - p.lo_[a]) / (p.n_[a] - 1);
  }
  for (float v : p.values_)
    if (!std::isfinite(v)) throwAt(path, "damaged shape prior (non-finite value)");
  return p;
}

Mesh ShapePrior::mesh(const Eigen::VectorXd& code, const Eigen::Vector3d& size) const {
  if (code.size() != dims_)
    throw Error("shape prior: code has " + std::to_string(code.size()) + " values, the prior " + std::to_string(dims_));
  const size_t G = static_cast<size_t>(n_[0]) * n_[1] * n_[2];
  std::vector<double> phi(G);
  for (int k = 0; k < n_[2]; ++k)
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i) phi[node(i, j, k)] = nodeValue(i, j, k, code);
  auto position = [&](size_t n) {
    const int i = static_cast<int>(n % n_[0]), j = static_cast<int>((n / n_[0]) % n_[1]),
              k = static_cast<int>(n / (static_cast<size_t>(n_[0]) * n_[1]));
    return Eigen::Vector3d((lo_[0] + i * cell_[0]) * size.x(), (lo_[1] + j * cell_[1]) * size.y(),
                           (lo_[2] + k * cell_[2]) * size.z());
  };
  Mesh out;
  std::unordered_map<std::uint64_t, int> edge_vertex;
  auto crossing = [&](size_t a, size_t b) {
    if (a > b) std::swap(a, b);
    const std::uint64_t key = static_cast<std::uint64_t>(a) * G + b;
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    const double t = phi[a] / (phi[a] - phi[b]);
    out.vertices.push_back(position(a) + t * (position(b) - position(a)));
    const int id = static_cast<int>(out.vertices.size()) - 1;
    edge_vertex.emplace(key, id);
    return id;
  };
  auto addFace = [&](int a, int b, int c, const Eigen::Vector3d& outward) {
    const Eigen::Vector3d nrm = (out.vertices[b] - out.vertices[a]).cross(out.vertices[c] - out.vertices[a]);
    if (nrm.dot(outward) < 0) std::swap(b, c);
    if (a != b && b != c && a != c) out.faces.push_back({a, b, c});
  };
  // Six tetrahedra round the cube diagonal 0-7 (corner bits x = 1, y = 2, z = 4): neighbouring cubes
  // split their shared faces the same way, so the surface has no cracks.
  static const int kTets[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};
  for (int k = 0; k + 1 < n_[2]; ++k)
    for (int j = 0; j + 1 < n_[1]; ++j)
      for (int i = 0; i + 1 < n_[0]; ++i) {
        size_t corner[8];
        int inside = 0;
        for (int c = 0; c < 8; ++c) {
          corner[c] = node(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
          inside += phi[corner[c]] < 0;
        }
        if (inside == 0 || inside == 8) continue;  // no tetrahedron of the cube crosses the surface
        for (const auto& tet : kTets) {
          size_t in[4], outv[4];
          int ni = 0, no = 0;
          for (int v : tet) (phi[corner[v]] < 0 ? in[ni++] : outv[no++]) = corner[v];
          if (ni == 0 || no == 0) continue;
          Eigen::Vector3d ci = Eigen::Vector3d::Zero(), co = Eigen::Vector3d::Zero();
          for (int a = 0; a < ni; ++a) ci += position(in[a]) / ni;
          for (int a = 0; a < no; ++a) co += position(outv[a]) / no;
          const Eigen::Vector3d outward = co - ci;
          if (ni == 1) {
            addFace(crossing(in[0], outv[0]), crossing(in[0], outv[1]), crossing(in[0], outv[2]), outward);
          } else if (no == 1) {
            addFace(crossing(outv[0], in[0]), crossing(outv[0], in[1]), crossing(outv[0], in[2]), outward);
          } else {
            const int ac = crossing(in[0], outv[0]), ad = crossing(in[0], outv[1]), bd = crossing(in[1], outv[1]),
                      bc = crossing(in[1], outv[0]);
            addFace(ac, ad, bd, outward);
            addFace(ac, bd, bc, outward);
          }
        }
      }
  return out;
}

std::vector<Eigen::Vector3d> ShapePrior::surfaceSamples(const Eigen::VectorXd& code, const Eigen::Vector3d& size, int n,
                                                        std::uint64_t seed) const {
  return shape::surfaceSamples(mesh(code, size), n, seed);
}

}  // namespace beslam::recon::shape
