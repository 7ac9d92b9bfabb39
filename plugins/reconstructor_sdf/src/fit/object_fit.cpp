#include "fit/object_fit.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
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

namespace {

// Why fitObject cannot fit these inputs (none when it can).
std::optional<std::string> inputProblem(const shape::ShapePrior& prior, const Eigen::Vector3d& size,
                                        const Eigen::VectorXd& code0, const Eigen::Isometry3d& T_world_obj_init,
                                        const FitObservations& obs, const FitOptions& options) {
  const int K = prior.dimensions();
  std::string why;
  if (!options.validate(&why)) return "bad fit options: " + why;
  if (K < 1 || K > kMaxFitDims)
    return "the shape prior has " + std::to_string(K) + " dimensions (1.." + std::to_string(kMaxFitDims) +
           " supported)";
  if (code0.size() != K || !code0.allFinite()) return "initial code must be " + std::to_string(K) + " finite values";
  if (!(size.allFinite() && size.minCoeff() > 0)) return "size must be positive";
  if (!T_world_obj_init.matrix().allFinite()) return "initial pose is not finite";
  if (obs.T_world_obj_boxes && !obs.T_world_obj_boxes->matrix().allFinite()) return "the boxes' pose is not finite";
  const size_t n = obs.p_world.size();
  if (n == 0 && obs.rays.empty() && obs.silhouette.empty()) return "no surface observations";
  if (!obs.weight.empty() && obs.weight.size() != n)
    return std::to_string(obs.weight.size()) + " weights for " + std::to_string(n) + " observations";
  for (size_t i = 0; i < n; ++i) {
    if (!obs.p_world[i].allFinite()) return "observation " + std::to_string(i) + " is not finite";
    if (!obs.weight.empty() && !(obs.weight[i] > 0 && obs.weight[i] <= 1))
      return "weight " + std::to_string(i) + " is outside (0, 1]";
  }
  for (size_t j = 0; j < obs.rays.size(); ++j) {
    const DepthRay& ray = obs.rays[j];
    if (!(ray.origin_world.allFinite() && ray.direction_world.allFinite() && std::isfinite(ray.depth_m) &&
          ray.depth_m > 0 && std::abs(ray.direction_world.norm() - 1) < 1e-6))
      return "ray " + std::to_string(j) + " is not finite, has no positive depth or no unit direction";
    if (!(ray.weight > 0 && ray.weight <= 1)) return "ray " + std::to_string(j) + " weight is outside (0, 1]";
  }
  for (size_t k = 0; k < obs.silhouette.size(); ++k) {
    const SilhouetteRay& ray = obs.silhouette[k];
    if (!(ray.origin_world.allFinite() && ray.direction_world.allFinite() &&
          std::abs(ray.direction_world.norm() - 1) < 1e-6))
      return "silhouette ray " + std::to_string(k) + " is not finite or has no unit direction";
    if (!(ray.weight > 0 && ray.weight <= 1))
      return "silhouette ray " + std::to_string(k) + " weight is outside (0, 1]";
  }
  if (n + obs.rays.size() + obs.silhouette.size() < 4) return "fewer than 4 surface observations";
  return std::nullopt;
}

// fitObject's solve, in the frame of the initial estimate: the unknowns are the pose update (angle-axis,
// translation), the code and the log of the size's scale; two stages, each a Ceres problem of the
// observations' residuals on them.
class ObjectFit {
 public:
  ObjectFit(const shape::ShapePrior& prior, const Eigen::Isometry3d& T_world_obj_init, const Eigen::Vector3d& size,
            const Eigen::VectorXd& code0, const FitObservations& obs, const FitOptions& options)
      : prior_(prior),
        K_(prior.dimensions()),
        T_world_obj_init_(T_world_obj_init),
        T_obj_world_init_(T_world_obj_init.inverse()),
        size_(size),
        obs_(obs),
        options_(options),
        p0_(obs.p_world.size()),
        code_(code0) {
    for (size_t i = 0; i < p0_.size(); ++i) p0_[i] = T_obj_world_init_ * obs.p_world[i];
  }

  // Stage 0 holds the code (and the size) and widens the Huber kernels 4 times; stage 1 frees the code (and
  // the size with fit_size). False (with why) when Ceres' solution is not usable.
  bool solveStage(int stage, std::string& why);
  // The estimate, its cost and how well it agrees with the observations (ok is left to the caller).
  FitResult result() const;

 private:
  void addSurfaceResiduals(ceres::Problem& problem, int stage);
  void addBoxPrior(ceres::Problem& problem);
  void addDepthResiduals(ceres::Problem& problem, int stage);
  void addSilhouetteResiduals(ceres::Problem& problem, int stage);
  void addPriorsAndConstants(ceres::Problem& problem, int stage);

  const shape::ShapePrior& prior_;
  const int K_;
  const Eigen::Isometry3d& T_world_obj_init_;
  const Eigen::Isometry3d T_obj_world_init_;
  const Eigen::Vector3d& size_;
  const FitObservations& obs_;
  const FitOptions& options_;
  std::vector<Eigen::Vector3d> p0_;  // the surface observations in the initial object frame

  double pose_[6] = {0, 0, 0, 0, 0, 0};
  double log_size_[3] = {0, 0, 0};
  Eigen::VectorXd code_;
  int iterations_ = 0;
  double cost_ = 0;
};

void ObjectFit::addSurfaceResiduals(ceres::Problem& problem, int stage) {
  const double huber = stage == 0 ? 4 * options_.huber_m : options_.huber_m;
  for (size_t i = 0; i < p0_.size(); ++i) {
    const double w = obs_.weight.empty() ? 1.0 : obs_.weight[i];
    const double scale = std::sqrt(options_.lambda_surface * w) / options_.sigma_m;
    problem.AddResidualBlock(surfaceCostFor(K_, prior_, p0_[i], size_, scale), new ceres::HuberLoss(huber * scale),
                             pose_, code_.data(), log_size_);
  }
}

void ObjectFit::addBoxPrior(ceres::Problem& problem) {
  const Eigen::Isometry3d D_boxes = T_obj_world_init_ * *obs_.T_world_obj_boxes;
  const double yaw = std::atan2(D_boxes.linear()(1, 0), D_boxes.linear()(0, 0));
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<BoxPriorResidual, 4, 6>(new BoxPriorResidual{
                               D_boxes.translation(), yaw, options_.box_sigma_m, options_.box_sigma_yaw}),
                           nullptr, pose_);
}

void ObjectFit::addDepthResiduals(ceres::Problem& problem, int stage) {
  for (const DepthRay& ray : obs_.rays) {
    const double scale = std::sqrt(options_.lambda_render * ray.weight) / options_.sigma_depth_m;
    problem.AddResidualBlock(depthCostFor(K_, prior_, T_obj_world_init_ * ray.origin_world,
                                          T_obj_world_init_.linear() * ray.direction_world, size_, ray.depth_m, scale),
                             new ceres::HuberLoss((stage == 0 ? 4 : 1) * options_.huber_depth_m * scale), pose_,
                             code_.data(), log_size_);
  }
}

void ObjectFit::addSilhouetteResiduals(ceres::Problem& problem, int stage) {
  // The estimate at the start of this solve: the level's metres per unit is taken there.
  const Eigen::Isometry3d T_obj_world_now = poseUpdate(pose_).inverse() * T_obj_world_init_;
  const double size_now[3] = {size_.x() * std::exp(log_size_[0]), size_.y() * std::exp(log_size_[1]),
                              size_.z() * std::exp(log_size_[2])};
  for (const SilhouetteRay& ray : obs_.silhouette) {
    const Eigen::Vector3d o = T_obj_world_now * ray.origin_world, u = T_obj_world_now.linear() * ray.direction_world;
    const double ov[3] = {o.x(), o.y(), o.z()}, uv[3] = {u.x(), u.y(), u.z()};
    const double scale = std::sqrt(options_.lambda_silhouette * ray.weight) / options_.sigma_silhouette_m;
    const double metres = metresPerLevel(prior_, ov, uv, size_now, code_.data());
    problem.AddResidualBlock(
        silhouetteCostFor(K_, prior_, T_obj_world_init_ * ray.origin_world,
                          T_obj_world_init_.linear() * ray.direction_world, size_, ray.inside, scale * metres),
        new ceres::HuberLoss((stage == 0 ? 4 : 1) * options_.huber_silhouette_m * scale), pose_, code_.data(),
        log_size_);
  }
}

// The code prior, which blocks are held in this stage, the size prior, and yaw_only's pose manifold.
void ObjectFit::addPriorsAndConstants(ceres::Problem& problem, int stage) {
  if (options_.lambda_code > 0)
    problem.AddResidualBlock(new DiagonalPrior(std::sqrt(options_.lambda_code) * prior_.codeStd().cwiseInverse()),
                             nullptr, code_.data());
  if (stage == 0) problem.SetParameterBlockConstant(code_.data());
  if (options_.fit_size && stage > 0) {
    problem.AddResidualBlock(
        new DiagonalPrior(Eigen::Vector3d::Constant(std::sqrt(options_.lambda_size) / options_.size_sigma)), nullptr,
        log_size_);
  } else {
    problem.SetParameterBlockConstant(log_size_);
  }
  if (options_.yaw_only) problem.SetManifold(pose_, new ceres::SubsetManifold(6, {0, 1}));
}

bool ObjectFit::solveStage(int stage, std::string& why) {
  ceres::Problem problem;
  addSurfaceResiduals(problem, stage);
  if (obs_.T_world_obj_boxes) addBoxPrior(problem);
  if (options_.lambda_render > 0) addDepthResiduals(problem, stage);
  if (options_.lambda_silhouette > 0) addSilhouetteResiduals(problem, stage);
  addPriorsAndConstants(problem, stage);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.max_num_iterations = options_.max_iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    why = "solver failed: " + summary.message;
    return false;
  }
  iterations_ += static_cast<int>(summary.iterations.size());
  cost_ = summary.final_cost;
  return true;
}

FitResult ObjectFit::result() const {
  FitResult r;
  r.T_world_obj = T_world_obj_init_ * poseUpdate(pose_);
  r.size = size_.cwiseProduct(Eigen::Vector3d(std::exp(log_size_[0]), std::exp(log_size_[1]), std::exp(log_size_[2])));
  r.code = code_;
  r.cost = 2 * cost_;  // Ceres reports half the sum of squares
  r.iterations = iterations_;
  const Eigen::Isometry3d T_obj_world = r.T_world_obj.inverse();
  const size_t n = obs_.p_world.size();
  double sum2 = 0;
  for (size_t i = 0; i < n; ++i) {
    const double d = prior_.distance(T_obj_world * obs_.p_world[i], r.size, r.code);
    sum2 += d * d;
    if (std::abs(d) < options_.inlier_m) ++r.inliers;
  }
  r.rms_m = n ? std::sqrt(sum2 / n) : 0.0;
  for (const SilhouetteRay& ray : obs_.silhouette) {
    const Eigen::Vector3d o = T_obj_world * ray.origin_world, u = T_obj_world.linear() * ray.direction_world;
    const double ov[3] = {o.x(), o.y(), o.z()}, uv[3] = {u.x(), u.y(), u.z()};
    const double s[3] = {r.size.x(), r.size.y(), r.size.z()};
    double level = 0;
    const double metres = metresPerLevel(prior_, ov, uv, s, r.code.data(), &level);  // one search for both
    const double violation = (ray.inside ? level : -level) * metres;
    if (violation < options_.inlier_m) ++r.silhouette_agree;
  }
  return r;
}

}  // namespace

FitResult fitObject(const shape::ShapePrior& prior, const Eigen::Isometry3d& T_world_obj_init,
                    const Eigen::Vector3d& size, const Eigen::VectorXd& code_init, const FitObservations& obs,
                    const FitOptions& options) {
  const int K = prior.dimensions();
  const Eigen::VectorXd code0 = code_init.size() == 0 ? Eigen::VectorXd::Zero(K) : code_init;
  if (const auto why = inputProblem(prior, size, code0, T_world_obj_init, obs, options))
    return failed(T_world_obj_init, size, code0, *why);

  ObjectFit fit(prior, T_world_obj_init, size, code0, obs, options);
  try {
    for (int stage = 0; stage < 2; ++stage) {
      std::string why;
      if (!fit.solveStage(stage, why)) return failed(T_world_obj_init, size, code0, why);
    }
  } catch (const std::exception& e) {
    return failed(T_world_obj_init, size, code0, std::string("solver failed: ") + e.what());
  }

  FitResult r = fit.result();
  if (!(r.T_world_obj.matrix().allFinite() && r.code.allFinite() && r.size.allFinite()))
    return failed(T_world_obj_init, size, code0, "solver returned a non-finite result");
  r.ok = true;
  return r;
}

}  // namespace beslam::recon::fit
