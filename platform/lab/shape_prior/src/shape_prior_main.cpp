// beslam-shape-prior (also `beslam shape-prior ...`): the car shape prior of reconstructor_sdf.
//   train --out FILE [--cars 200] [--seed 1] [--dims 0] [--grid 44,22,22] [--margin 0.15]
//   info FILE
//   eval FILE [--cars 40] [--seed 1] [--samples 1500] [--fit]
//   mesh FILE --size l,w,h [--code z1,z2,...] --out FILE.ply
// train: signed-distance grids of procedural cars drawn from the TRAINING ranges (car_set.hpp),
// PCA; same options give a byte-identical file. eval: held-out cars from the sequences' ranges, each
// reconstructed by least squares in code space (projection of its grid); prints the median and 90th
// percentile Chamfer distance in metres. --fit also fits each held-out car from simulated LiDAR-like and
// map-point-like observations and from a depth-map patch alone (car_set.hpp) and prints centre, yaw and Chamfer
// errors and the fit time. Errors: one line "beslam-shape-prior: error: ...", exit 1 (2 for usage).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "beslam/formats/error.hpp"
#include "beslam/sdk/cli_args.hpp"
#include "beslam/shape_prior/car_set.hpp"
#include "fit/object_fit.hpp"
#include "shape/shape_prior.hpp"

using beslam::recon::shape::ShapePrior;
namespace shape = beslam::recon::shape;
namespace fit = beslam::recon::fit;
namespace tools = beslam::recon::tools;

namespace {

constexpr const char* kUsage =
    "usage: beslam shape-prior <command> [options]\n"
    "\n"
    "  train --out FILE [--cars 200] [--seed 1] [--dims 0] [--grid 44,22,22] [--margin 0.15]\n"
    "        learn the car shape prior (dims 0: fewest reaching 99 % of the variance, at most 8)\n"
    "  info FILE\n"
    "        print a prior's grid, dimensions and explained variance\n"
    "  eval FILE [--cars 40] [--seed 1] [--samples 1500] [--fit]\n"
    "        Chamfer distance of held-out cars (sequence ranges) reconstructed from the prior;\n"
    "        --fit: also fit them from simulated LiDAR and map points\n"
    "  mesh FILE --size l,w,h [--code z1,...] --out FILE.ply\n"
    "        write the shape of a code (default: the mean) for a box size as a PLY mesh\n";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::vector<double> numbers(const std::string& key, const std::string& value) {
  std::vector<double> out;
  std::stringstream ss(value);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      out.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw UsageError(key + ": not a number list: " + value);
    }
  }
  return out;
}

long integer(const std::string& key, const std::string& value, long lo, long hi) {
  const auto v = numbers(key, value);
  if (v.size() != 1 || v[0] != static_cast<long>(v[0]) || v[0] < lo || v[0] > hi)
    throw UsageError(key + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
  return static_cast<long>(v[0]);
}

struct Args {
  std::string file;
  std::vector<std::pair<std::string, std::string>> options;
  std::vector<std::string> flags;
  std::string get(const std::string& key, const std::string& fallback) const {
    for (const auto& kv : options)
      if (kv.first == key) return kv.second;
    return fallback;
  }
  bool has(const std::string& flag) const { return std::find(flags.begin(), flags.end(), flag) != flags.end(); }
};

Args parse(const std::vector<std::string>& a, size_t from, const std::vector<std::string>& keys,
           const std::vector<std::string>& flag_names, bool wants_file) {
  Args out;
  for (size_t i = from; i < a.size(); ++i) {
    if (std::find(flag_names.begin(), flag_names.end(), a[i]) != flag_names.end()) {
      out.flags.push_back(a[i]);
    } else if (std::find(keys.begin(), keys.end(), a[i]) != keys.end()) {
      if (i + 1 >= a.size()) throw UsageError(a[i] + " needs a value");
      out.options.emplace_back(a[i], a[i + 1]);
      ++i;
    } else if (wants_file && out.file.empty() && a[i].rfind("--", 0) != 0) {
      out.file = a[i];
    } else {
      throw UsageError("unknown argument " + a[i]);
    }
  }
  if (wants_file && out.file.empty()) throw UsageError("missing FILE");
  return out;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5));
  return v[i];
}

int train(const Args& a) {
  const std::string out = a.get("--out", "");
  if (out.empty()) throw UsageError("train needs --out FILE");
  const int cars = static_cast<int>(integer("--cars", a.get("--cars", "200"), 2, 100000));
  shape::TrainOptions opt;
  opt.seed = static_cast<std::uint64_t>(integer("--seed", a.get("--seed", "1"), 0, 1L << 40));
  opt.dims = static_cast<int>(integer("--dims", a.get("--dims", "0"), 0, 64));
  const auto grid = numbers("--grid", a.get("--grid", "44,22,22"));
  if (grid.size() != 3) throw UsageError("--grid needs NX,NY,NZ");
  for (int i = 0; i < 3; ++i) opt.grid[i] = static_cast<int>(grid[i]);
  opt.margin = numbers("--margin", a.get("--margin", "0.15")).at(0);
  const auto t0 = std::chrono::steady_clock::now();
  const ShapePrior prior = shape::trainShapePrior(tools::bodies(tools::trainingCars(cars, opt.seed)), opt);
  prior.save(out);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%s: %d cars, grid %dx%dx%d, %d dimensions (%.1f %% of the variance), %.1f s\n", out.c_str(), cars,
              opt.grid[0], opt.grid[1], opt.grid[2], prior.dimensions(), 100 * prior.explainedVariance().sum(), s);
  return 0;
}

int info(const Args& a) {
  const ShapePrior p = ShapePrior::load(a.file);
  const auto n = p.gridSize();
  std::printf("%s: shape prior version %u\n  grid %d x %d x %d over normalised [%.3f, %.3f]\n", a.file.c_str(),
              ShapePrior::kVersion, n[0], n[1], n[2], p.gridLo().x(), p.gridHi().x());
  std::printf("  trained on %d cars, seed %llu\n  %d dimensions:", p.trainingShapes(),
              static_cast<unsigned long long>(p.seed()), p.dimensions());
  double acc = 0;
  for (int k = 0; k < p.dimensions(); ++k) {
    acc += p.explainedVariance()(k);
    std::printf(" [std %.3f, %.1f %%]", p.codeStd()(k), 100 * acc);
  }
  std::printf("\n");
  return 0;
}

int eval(const Args& a) {
  const ShapePrior prior = ShapePrior::load(a.file);
  const int cars = static_cast<int>(integer("--cars", a.get("--cars", "40"), 1, 100000));
  const auto seed = static_cast<std::uint64_t>(integer("--seed", a.get("--seed", "1"), 0, 1L << 40));
  const int samples = static_cast<int>(integer("--samples", a.get("--samples", "1500"), 10, 1000000));
  const auto held = tools::heldOutCars(cars, seed);
  std::vector<double> chamfer, mean_chamfer;
  for (size_t i = 0; i < held.size(); ++i) {
    const auto& car = held[i].body;
    const Eigen::VectorXd z = prior.project(prior.sampleGrid(car));
    chamfer.push_back(shape::chamferDistance(prior.mesh(z, car.size), car.mesh, samples, 100 + i));
    mean_chamfer.push_back(shape::chamferDistance(prior.mesh(Eigen::VectorXd::Zero(prior.dimensions()), car.size),
                                                  car.mesh, samples, 100 + i));
  }
  std::printf("held-out cars: %d (sequence ranges, seed %llu), %d samples a mesh\n", cars,
              static_cast<unsigned long long>(seed), samples);
  std::printf("  code by least squares: Chamfer median %.4f m, 90 %% %.4f m, max %.4f m\n", percentile(chamfer, 0.5),
              percentile(chamfer, 0.9), percentile(chamfer, 1.0));
  std::printf("  mean shape (z = 0):     Chamfer median %.4f m, 90 %% %.4f m\n", percentile(mean_chamfer, 0.5),
              percentile(mean_chamfer, 0.9));
  if (!a.has("--fit")) return 0;
  struct Case {
    const char* name;
    int points;  // 0: a 16 x 8 depth-map patch instead of points
    double noise;
    fit::FitOptions opt;
  };
  fit::FitOptions lidar, sparse;
  sparse.sigma_m = 0.05;
  sparse.huber_m = 0.10;
  const Case cases[] = {{"LiDAR-like (200 pts, 2 cm)", 200, 0.02, lidar},
                        {"map points (50 pts, 5 cm)", 50, 0.05, sparse},
                        {"a depth-map patch (16 x 8 rays, 5 cm)", 0, 0.05, sparse}};
  for (const Case& c : cases) {
    std::vector<double> centre, yaw, ch, ms;
    int failed = 0;
    for (size_t i = 0; i < held.size(); ++i) {
      const auto& car = held[i].body;
      shape::Random rng(seed * 1000 + i);
      // Sensor 6-10 m away at 1.7 m above the road, any bearing; pose perturbed by 0.5 m and 10 deg.
      const double bearing = rng.uniform(-M_PI, M_PI), range = rng.uniform(6, 10);
      const Eigen::Vector3d sensor(range * std::cos(bearing), range * std::sin(bearing), 1.7 - car.size.z() / 2);
      const auto pts = tools::visibleSurfacePoints(car.mesh, sensor, c.points, c.noise, seed * 7919 + i);
      const auto rays = c.points ? std::vector<tools::ObjectRay>()
                                 : tools::depthPatch(car.mesh, sensor, car.size, 16, 8, c.noise, seed * 7919 + i);
      Eigen::Isometry3d T_true = Eigen::Isometry3d::Identity();
      T_true.linear() = Eigen::AngleAxisd(rng.uniform(-M_PI, M_PI), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      T_true.translation() = Eigen::Vector3d(rng.uniform(-20, 20), rng.uniform(-20, 20), car.size.z() / 2);
      fit::FitObservations obs;
      for (const auto& p : pts) obs.p_world.push_back(T_true * p);
      for (const auto& ray : rays)
        obs.rays.push_back({T_true * sensor, T_true.linear() * ray.direction, ray.depth, 1.0});
      const double a0 = rng.uniform(0, 2 * M_PI);
      Eigen::Isometry3d T_init = T_true;
      T_init.translation() += 0.5 * Eigen::Vector3d(std::cos(a0), std::sin(a0), 0);
      T_init.linear() =
          T_true.linear() * Eigen::AngleAxisd(10 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const auto t0 = std::chrono::steady_clock::now();
      const fit::FitResult r =
          fit::fitObject(prior, T_init, car.size, Eigen::VectorXd::Zero(prior.dimensions()), obs, c.opt);
      ms.push_back(1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      if (!r.ok) {
        ++failed;
        continue;
      }
      centre.push_back((r.T_world_obj.translation() - T_true.translation()).norm());
      const Eigen::Matrix3d dR = T_true.linear().transpose() * r.T_world_obj.linear();
      yaw.push_back(std::abs(std::atan2(dR(1, 0), dR(0, 0))) * 180 / M_PI);
      shape::Mesh m = prior.mesh(r.code, r.size);
      const Eigen::Isometry3d T_true_est = T_true.inverse() * r.T_world_obj;
      for (auto& v : m.vertices) v = T_true_est * v;
      ch.push_back(shape::chamferDistance(m, car.mesh, samples, 200 + i));
    }
    std::printf("fit from %s, init off by 0.5 m and 10 deg, %d failed:\n", c.name, failed);
    std::printf("  centre error median %.3f m, 90 %% %.3f m; |yaw error| median %.2f deg, 90 %% %.2f deg\n",
                percentile(centre, 0.5), percentile(centre, 0.9), percentile(yaw, 0.5), percentile(yaw, 0.9));
    std::printf("  Chamfer median %.4f m, 90 %% %.4f m; fit time median %.1f ms, 90 %% %.1f ms\n", percentile(ch, 0.5),
                percentile(ch, 0.9), percentile(ms, 0.5), percentile(ms, 0.9));
  }
  return 0;
}

int mesh(const Args& a) {
  const ShapePrior prior = ShapePrior::load(a.file);
  const std::string out = a.get("--out", "");
  if (out.empty()) throw UsageError("mesh needs --out FILE.ply");
  const auto size = numbers("--size", a.get("--size", ""));
  if (size.size() != 3 || !(std::min({size[0], size[1], size[2]}) > 0))
    throw UsageError("--size needs three positive numbers l,w,h");
  Eigen::VectorXd z = Eigen::VectorXd::Zero(prior.dimensions());
  const std::string code = a.get("--code", "");
  if (!code.empty()) {
    const auto c = numbers("--code", code);
    if (static_cast<int>(c.size()) != prior.dimensions())
      throw UsageError("--code needs " + std::to_string(prior.dimensions()) + " values");
    for (int k = 0; k < prior.dimensions(); ++k) z(k) = c[k];
  }
  const shape::Mesh m = prior.mesh(z, Eigen::Vector3d(size[0], size[1], size[2]));
  beslam::formats::writePlyMesh(out, m);
  std::printf("%s: %zu vertices, %zu faces\n", out.c_str(), m.vertices.size(), m.faces.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  const auto dispatch = [&]() -> int {
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
      std::cout << kUsage;
      return args.empty() ? 2 : 0;
    }
    const std::string& cmd = args[0];
    if (cmd == "train")
      return train(parse(args, 1, {"--out", "--cars", "--seed", "--dims", "--grid", "--margin"}, {}, false));
    if (cmd == "info") return info(parse(args, 1, {}, {}, true));
    if (cmd == "eval") return eval(parse(args, 1, {"--cars", "--seed", "--samples"}, {"--fit"}, true));
    if (cmd == "mesh") return mesh(parse(args, 1, {"--size", "--code", "--out"}, {}, true));
    throw UsageError("unknown command " + cmd);
  };
  return beslam::cli::runMain<UsageError>(dispatch, std::cerr, kUsage,
                                          "beslam-shape-prior: error: ", "beslam-shape-prior: error: ");
}
