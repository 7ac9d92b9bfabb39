#include "fit/object_fit.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>
#include <memory>
#include <type_traits>

#include "fit/render_depth.hpp"
#include "fit/silhouette.hpp"

namespace beslam::recon::fit {
namespace {

// make(std::integral_constant<int, K>) for the runtime k in 1..kMaxFitDims: the code size is a template
// argument of Ceres' AutoDiffCostFunction. nullptr for another k.
template <int K = 1, class Make>
ceres::CostFunction* withDims(int k, const Make& make) {
  if constexpr (K > kMaxFitDims) {
    return nullptr;
  } else {
    return k == K ? make(std::integral_constant<int, K>{}) : withDims<K + 1>(k, make);
  }
}

// Pose block: angle-axis (3) then translation (3) of the update D, T_world_obj = T_init * D; the point in
// the object frame is D^-1 * p0 with p0 = T_init^-1 * p_world. Size block: log(size / size_init).
template <int K>
struct SurfaceResidual {
  const shape::ShapePrior* prior;
  Eigen::Vector3d p0, size0;
  double scale;

  template <typename T>
  bool operator()(const T* pose, const T* code, const T* log_size, T* r) const {
    const T d[3] = {T(p0.x()) - pose[3], T(p0.y()) - pose[4], T(p0.z()) - pose[5]};
    const T minus_aa[3] = {-pose[0], -pose[1], -pose[2]};
    T p_obj[3];
    ceres::AngleAxisRotatePoint(minus_aa, d, p_obj);
    using std::exp;
    const T size[3] = {size0.x() * exp(log_size[0]), size0.y() * exp(log_size[1]), size0.z() * exp(log_size[2])};
    r[0] = scale * prior->distanceSized(p_obj, size, code);
    return true;
  }
};

// A ray given in the initial object frame (o0, u0) in the frame of the updated pose, and the updated size.
template <typename T>
void rayInObject(const T* pose, const T* log_size, const Eigen::Vector3d& o0, const Eigen::Vector3d& u0,
                 const Eigen::Vector3d& size0, T o_obj[3], T u_obj[3], T size[3]) {
  const T d[3] = {T(o0.x()) - pose[3], T(o0.y()) - pose[4], T(o0.z()) - pose[5]};
  const T u[3] = {T(u0.x()), T(u0.y()), T(u0.z())};
  const T minus_aa[3] = {-pose[0], -pose[1], -pose[2]};
  ceres::AngleAxisRotatePoint(minus_aa, d, o_obj);
  ceres::AngleAxisRotatePoint(minus_aa, u, u_obj);
  using std::exp;
  for (int a = 0; a < 3; ++a) size[a] = size0[a] * exp(log_size[a]);
}

template <int K>
struct DepthResidual {
  const shape::ShapePrior* prior;
  Eigen::Vector3d o0, u0, size0;  // ray in the initial object frame
  double depth, scale;

  template <typename T>
  bool operator()(const T* pose, const T* code, const T* log_size, T* r) const {
    T o_obj[3], u_obj[3], size[3];
    rayInObject(pose, log_size, o0, u0, size0, o_obj, u_obj, size);
    T rendered;
    if (!renderDepth(*prior, o_obj, u_obj, size, code, &rendered)) {
      r[0] = T(0.0);  // a miss: no information in this iteration
      return true;
    }
    r[0] = scale * (rendered - depth);
    return true;
  }
};

template <int K>
ceres::CostFunction* depthCost(const shape::ShapePrior& prior, const Eigen::Vector3d& o0, const Eigen::Vector3d& u0,
                               const Eigen::Vector3d& size0, double depth, double scale) {
  return new ceres::AutoDiffCostFunction<DepthResidual<K>, 1, 6, K, 3>(
      new DepthResidual<K>{&prior, o0, u0, size0, depth, scale});
}

ceres::CostFunction* depthCostFor(int k, const shape::ShapePrior& prior, const Eigen::Vector3d& o0,
                                  const Eigen::Vector3d& u0, const Eigen::Vector3d& size0, double depth, double scale) {
  return withDims(k, [&](auto dims) { return depthCost<decltype(dims)::value>(prior, o0, u0, size0, depth, scale); });
}

template <int K>
struct SilhouetteResidual {
  const shape::ShapePrior* prior;
  Eigen::Vector3d o0, u0, size0;  // ray in the initial object frame
  bool inside;
  double scale;  // 1 / sigma times the metres per level unit at the start

  template <typename T>
  bool operator()(const T* pose, const T* code, const T* log_size, T* r) const {
    T o_obj[3], u_obj[3], size[3];
    rayInObject(pose, log_size, o0, u0, size0, o_obj, u_obj, size);
    r[0] = scale * silhouetteViolation(*prior, o_obj, u_obj, size, code, inside);  // 0 on the right side
    return true;
  }
};

ceres::CostFunction* silhouetteCostFor(int k, const shape::ShapePrior& prior, const Eigen::Vector3d& o0,
                                       const Eigen::Vector3d& u0, const Eigen::Vector3d& size0, bool inside,
                                       double scale) {
  return withDims(k, [&](auto dims) -> ceres::CostFunction* {
    constexpr int D = decltype(dims)::value;
    return new ceres::AutoDiffCostFunction<SilhouetteResidual<D>, 1, 6, D, 3>(
        new SilhouetteResidual<D>{&prior, o0, u0, size0, inside, scale});
  });
}

class DiagonalPrior : public ceres::CostFunction {  // r_k = w_k * x_k
 public:
  explicit DiagonalPrior(Eigen::VectorXd w) : w_(std::move(w)) {
    set_num_residuals(static_cast<int>(w_.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(w_.size()));
  }
  bool Evaluate(double const* const* x, double* r, double** J) const override {
    const int n = static_cast<int>(w_.size());
    for (int k = 0; k < n; ++k) r[k] = w_(k) * x[0][k];
    if (J && J[0])
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < n; ++k) J[0][i * n + k] = i == k ? w_(k) : 0.0;
    return true;
  }

 private:
  Eigen::VectorXd w_;
};

// The boxes' pose as a prior on the update D (pose block): D_boxes = T_init^-1 * T_boxes. Residuals: the
// centre offset in the initial object frame over sigma_m, and the yaw about the object's z over
// sigma_yaw, wrapped into (-pi/2, pi/2] so a box facing backwards is no error.
struct BoxPriorResidual {
  Eigen::Vector3d t_boxes;
  double yaw_boxes, sigma_m, sigma_yaw;

  template <typename T>
  bool operator()(const T* pose, T* r) const {
    for (int k = 0; k < 3; ++k) r[k] = (pose[3 + k] - t_boxes[k]) / sigma_m;
    T dyaw = pose[2] - yaw_boxes;
    dyaw -= M_PI * std::round(shape::scalarPart(dyaw) / M_PI);
    r[3] = dyaw / sigma_yaw;
    return true;
  }
};

template <int K>
ceres::CostFunction* surfaceCost(const shape::ShapePrior& prior, const Eigen::Vector3d& p0,
                                 const Eigen::Vector3d& size0, double scale) {
  return new ceres::AutoDiffCostFunction<SurfaceResidual<K>, 1, 6, K, 3>(
      new SurfaceResidual<K>{&prior, p0, size0, scale});
}

ceres::CostFunction* surfaceCostFor(int k, const shape::ShapePrior& prior, const Eigen::Vector3d& p0,
                                    const Eigen::Vector3d& size0, double scale) {
  return withDims(k, [&](auto dims) { return surfaceCost<decltype(dims)::value>(prior, p0, size0, scale); });
}

// The update D of the pose block (angle-axis, translation).
Eigen::Isometry3d poseUpdate(const double pose[6]) {
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d aa(pose[0], pose[1], pose[2]);
  if (aa.norm() > 0) D.linear() = Eigen::AngleAxisd(aa.norm(), aa.normalized()).toRotationMatrix();
  D.translation() = Eigen::Vector3d(pose[3], pose[4], pose[5]);
  return D;
}

FitResult failed(const Eigen::Isometry3d& T, const Eigen::Vector3d& size, const Eigen::VectorXd& code,
                 const std::string& why) {
  FitResult r;
  r.ok = false;
  r.why = why;
  r.T_world_obj = T;
  r.size = size;
  r.code = code;
  return r;
}

}  // namespace

bool FitOptions::validate(std::string* why) const {
  auto bad = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(lambda_surface > 0 && std::isfinite(lambda_surface))) return bad("lambda_surface must be positive");
  if (!(lambda_code >= 0 && std::isfinite(lambda_code))) return bad("lambda_code must be 0 or more");
  if (!(sigma_m > 0 && std::isfinite(sigma_m))) return bad("sigma_m must be positive");
  if (!(huber_m > 0 && std::isfinite(huber_m))) return bad("huber_m must be positive");
  if (max_iterations < 1) return bad("max_iterations must be at least 1");
  if (fit_size && !(lambda_size > 0 && size_sigma > 0)) return bad("fit_size needs lambda_size and size_sigma > 0");
  if (!(inlier_m > 0)) return bad("inlier_m must be positive");
  if (!(box_sigma_m > 0 && box_sigma_yaw > 0)) return bad("box_sigma_m and box_sigma_yaw must be positive");
  if (!(lambda_render >= 0 && sigma_depth_m > 0 && huber_depth_m > 0))
    return bad("lambda_render must be 0 or more, sigma_depth_m and huber_depth_m positive");
  if (!(lambda_silhouette >= 0 && sigma_silhouette_m > 0 && huber_silhouette_m > 0))
    return bad("lambda_silhouette must be 0 or more, sigma_silhouette_m and huber_silhouette_m positive");
  return true;
}

FitResult fitObject(const shape::ShapePrior& prior, const Eigen::Isometry3d& T_world_obj_init,
                    const Eigen::Vector3d& size, const Eigen::VectorXd& code_init, const FitObservations& obs,
                    const FitOptions& options) {
  const int K = prior.dimensions();
  const Eigen::VectorXd code0 = code_init.size() == 0 ? Eigen::VectorXd::Zero(K) : code_init;
  std::string why;
  if (!options.validate(&why)) return failed(T_world_obj_init, size, code0, "bad fit options: " + why);
  if (K < 1 || K > kMaxFitDims)
    return failed(
        T_world_obj_init, size, code0,
        "the shape prior has " + std::to_string(K) + " dimensions (1.." + std::to_string(kMaxFitDims) + " supported)");
  if (code0.size() != K || !code0.allFinite())
    return failed(T_world_obj_init, size, code0, "initial code must be " + std::to_string(K) + " finite values");
  if (!(size.allFinite() && size.minCoeff() > 0)) return failed(T_world_obj_init, size, code0, "size must be positive");
  if (!T_world_obj_init.matrix().allFinite())
    return failed(T_world_obj_init, size, code0, "initial pose is not finite");
  if (obs.T_world_obj_boxes && !obs.T_world_obj_boxes->matrix().allFinite())
    return failed(T_world_obj_init, size, code0, "the boxes' pose is not finite");
  const size_t n = obs.p_world.size();
  if (n == 0 && obs.rays.empty() && obs.silhouette.empty())
    return failed(T_world_obj_init, size, code0, "no surface observations");
  if (!obs.weight.empty() && obs.weight.size() != n)
    return failed(T_world_obj_init, size, code0,
                  std::to_string(obs.weight.size()) + " weights for " + std::to_string(n) + " observations");
  for (size_t i = 0; i < n; ++i) {
    if (!obs.p_world[i].allFinite())
      return failed(T_world_obj_init, size, code0, "observation " + std::to_string(i) + " is not finite");
    if (!obs.weight.empty() && !(obs.weight[i] > 0 && obs.weight[i] <= 1))
      return failed(T_world_obj_init, size, code0, "weight " + std::to_string(i) + " is outside (0, 1]");
  }
  for (size_t j = 0; j < obs.rays.size(); ++j) {
    const DepthRay& ray = obs.rays[j];
    if (!(ray.origin_world.allFinite() && ray.direction_world.allFinite() && std::isfinite(ray.depth_m) &&
          ray.depth_m > 0 && std::abs(ray.direction_world.norm() - 1) < 1e-6))
      return failed(T_world_obj_init, size, code0,
                    "ray " + std::to_string(j) + " is not finite, has no positive depth or no unit direction");
    if (!(ray.weight > 0 && ray.weight <= 1))
      return failed(T_world_obj_init, size, code0, "ray " + std::to_string(j) + " weight is outside (0, 1]");
  }
  for (size_t k = 0; k < obs.silhouette.size(); ++k) {
    const SilhouetteRay& ray = obs.silhouette[k];
    if (!(ray.origin_world.allFinite() && ray.direction_world.allFinite() &&
          std::abs(ray.direction_world.norm() - 1) < 1e-6))
      return failed(T_world_obj_init, size, code0,
                    "silhouette ray " + std::to_string(k) + " is not finite or has no unit direction");
    if (!(ray.weight > 0 && ray.weight <= 1))
      return failed(T_world_obj_init, size, code0, "silhouette ray " + std::to_string(k) + " weight is outside (0, 1]");
  }
  if (n + obs.rays.size() + obs.silhouette.size() < 4)
    return failed(T_world_obj_init, size, code0, "fewer than 4 surface observations");

  const Eigen::Isometry3d T_obj_world_init = T_world_obj_init.inverse();
  std::vector<Eigen::Vector3d> p0(n);
  for (size_t i = 0; i < n; ++i) p0[i] = T_obj_world_init * obs.p_world[i];

  double pose[6] = {0, 0, 0, 0, 0, 0};
  double log_size[3] = {0, 0, 0};
  Eigen::VectorXd code = code0;
  int iterations = 0;
  double cost = 0;
  try {
    for (int stage = 0; stage < 2; ++stage) {
      const double huber = stage == 0 ? 4 * options.huber_m : options.huber_m;
      ceres::Problem problem;
      for (size_t i = 0; i < n; ++i) {
        const double w = obs.weight.empty() ? 1.0 : obs.weight[i];
        const double scale = std::sqrt(options.lambda_surface * w) / options.sigma_m;
        problem.AddResidualBlock(surfaceCostFor(K, prior, p0[i], size, scale), new ceres::HuberLoss(huber * scale),
                                 pose, code.data(), log_size);
      }
      if (obs.T_world_obj_boxes) {
        const Eigen::Isometry3d D_boxes = T_obj_world_init * *obs.T_world_obj_boxes;
        const double yaw = std::atan2(D_boxes.linear()(1, 0), D_boxes.linear()(0, 0));
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<BoxPriorResidual, 4, 6>(new BoxPriorResidual{
                                     D_boxes.translation(), yaw, options.box_sigma_m, options.box_sigma_yaw}),
                                 nullptr, pose);
      }
      if (options.lambda_render > 0)
        for (const DepthRay& ray : obs.rays) {
          const double scale = std::sqrt(options.lambda_render * ray.weight) / options.sigma_depth_m;
          problem.AddResidualBlock(
              depthCostFor(K, prior, T_obj_world_init * ray.origin_world,
                           T_obj_world_init.linear() * ray.direction_world, size, ray.depth_m, scale),
              new ceres::HuberLoss((stage == 0 ? 4 : 1) * options.huber_depth_m * scale), pose, code.data(), log_size);
        }
      if (options.lambda_silhouette > 0) {
        // The estimate at the start of this solve: the level's metres per unit is taken there.
        const Eigen::Isometry3d T_obj_world_now = poseUpdate(pose).inverse() * T_obj_world_init;
        const double size_now[3] = {size.x() * std::exp(log_size[0]), size.y() * std::exp(log_size[1]),
                                    size.z() * std::exp(log_size[2])};
        for (const SilhouetteRay& ray : obs.silhouette) {
          const Eigen::Vector3d o = T_obj_world_now * ray.origin_world,
                                u = T_obj_world_now.linear() * ray.direction_world;
          const double ov[3] = {o.x(), o.y(), o.z()}, uv[3] = {u.x(), u.y(), u.z()};
          const double scale = std::sqrt(options.lambda_silhouette * ray.weight) / options.sigma_silhouette_m;
          const double metres = metresPerLevel(prior, ov, uv, size_now, code.data());
          problem.AddResidualBlock(
              silhouetteCostFor(K, prior, T_obj_world_init * ray.origin_world,
                                T_obj_world_init.linear() * ray.direction_world, size, ray.inside, scale * metres),
              new ceres::HuberLoss((stage == 0 ? 4 : 1) * options.huber_silhouette_m * scale), pose, code.data(),
              log_size);
        }
      }
      if (options.lambda_code > 0)
        problem.AddResidualBlock(new DiagonalPrior(std::sqrt(options.lambda_code) * prior.codeStd().cwiseInverse()),
                                 nullptr, code.data());
      if (stage == 0) problem.SetParameterBlockConstant(code.data());
      if (options.fit_size && stage > 0) {
        problem.AddResidualBlock(
            new DiagonalPrior(Eigen::Vector3d::Constant(std::sqrt(options.lambda_size) / options.size_sigma)), nullptr,
            log_size);
      } else {
        problem.SetParameterBlockConstant(log_size);
      }
      if (options.yaw_only) problem.SetManifold(pose, new ceres::SubsetManifold(6, {0, 1}));
      ceres::Solver::Options so;
      so.linear_solver_type = ceres::DENSE_QR;
      so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
      so.max_num_iterations = options.max_iterations;
      so.num_threads = 1;
      so.logging_type = ceres::SILENT;
      ceres::Solver::Summary summary;
      ceres::Solve(so, &problem, &summary);
      if (!summary.IsSolutionUsable())
        return failed(T_world_obj_init, size, code0, "solver failed: " + summary.message);
      iterations += static_cast<int>(summary.iterations.size());
      cost = summary.final_cost;
    }
  } catch (const std::exception& e) {
    return failed(T_world_obj_init, size, code0, std::string("solver failed: ") + e.what());
  }

  FitResult r;
  r.T_world_obj = T_world_obj_init * poseUpdate(pose);
  r.size = size.cwiseProduct(Eigen::Vector3d(std::exp(log_size[0]), std::exp(log_size[1]), std::exp(log_size[2])));
  r.code = code;
  r.cost = 2 * cost;  // Ceres reports half the sum of squares
  r.iterations = iterations;
  const Eigen::Isometry3d T_obj_world = r.T_world_obj.inverse();
  double sum2 = 0;
  for (size_t i = 0; i < n; ++i) {
    const double d = prior.distance(T_obj_world * obs.p_world[i], r.size, r.code);
    sum2 += d * d;
    if (std::abs(d) < options.inlier_m) ++r.inliers;
  }
  r.rms_m = n ? std::sqrt(sum2 / n) : 0.0;
  for (const SilhouetteRay& ray : obs.silhouette) {
    const Eigen::Vector3d o = T_obj_world * ray.origin_world, u = T_obj_world.linear() * ray.direction_world;
    const double ov[3] = {o.x(), o.y(), o.z()}, uv[3] = {u.x(), u.y(), u.z()};
    const double s[3] = {r.size.x(), r.size.y(), r.size.z()};
    double level = 0;
    const double metres = metresPerLevel(prior, ov, uv, s, r.code.data(), &level);  // one search for both
    const double violation = (ray.inside ? level : -level) * metres;
    if (violation < options.inlier_m) ++r.silhouette_agree;
  }
  if (!(r.T_world_obj.matrix().allFinite() && r.code.allFinite() && r.size.allFinite()))
    return failed(T_world_obj_init, size, code0, "solver returned a non-finite result");
  r.ok = true;
  return r;
}

}  // namespace beslam::recon::fit
