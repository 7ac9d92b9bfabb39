#include "optimize/bundle_adjustment.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "optimize/cost_functions.hpp"
#include "optimize/schur_lm.hpp"
#include "optimize/se3.hpp"

namespace beslam::orb::optimize {
namespace {

struct Edge {
  KeyFrame* kf;
  MapPoint* mp;
  size_t idx;
  double* pose;
  double* point;
  std::unique_ptr<ReprojectionCost> cost;
  bool outlier = false;
};

// Parameter blocks live in two contiguous arrays in id order: Ceres orders blocks of an elimination
// group by address, so this keeps the solve (and the whole run) deterministic.
struct Problem {
  std::vector<KeyFrame*> moving, fixed;
  std::vector<MapPoint*> points;
  std::map<KeyFrame*, double*, IdLess<KeyFrame>> poses;
  std::map<MapPoint*, double*, IdLess<MapPoint>> positions;
  std::vector<double> pose_storage, point_storage;
  std::vector<Edge> edges;
  struct GroundEdge {
    double* pose;
    double* point;
    std::unique_ptr<ceres::CostFunction> cost;
  };
  std::vector<GroundEdge> ground_edges;
  std::vector<GroundEdge> range_edges;              // ObjectRangeCost, same shape
  std::vector<GroundEdge> anchor_edges;             // BoxCentreCost: pose and anchor
  std::vector<int32_t> anchor_ids;                  // parked cars with an anchor, increasing
  std::vector<double> anchor_storage;               // 3 numbers an anchor, in anchor_ids' order
  std::unique_ptr<objects::ObjectProblem> objects;  // object landmarks' nodes and factors (or none)

  void allocate() {
    std::vector<KeyFrame*> kfs(moving);
    kfs.insert(kfs.end(), fixed.begin(), fixed.end());
    std::sort(kfs.begin(), kfs.end(), IdLess<KeyFrame>());
    std::sort(points.begin(), points.end(), IdLess<MapPoint>());
    pose_storage.assign(7 * kfs.size(), 0.0);
    point_storage.assign(3 * points.size(), 0.0);
    for (size_t i = 0; i < kfs.size(); ++i) {
      poses[kfs[i]] = &pose_storage[7 * i];
      poseToParams(kfs[i]->T_cw, poses[kfs[i]]);
    }
    for (size_t i = 0; i < points.size(); ++i) {
      double* x = &point_storage[3 * i];
      positions[points[i]] = x;
      x[0] = points[i]->position.x();
      x[1] = points[i]->position.y();
      x[2] = points[i]->position.z();
    }
  }
};

double chi2(const Edge& e, bool* behind) {
  double r[2];
  const double* params[] = {e.pose, e.point};
  e.cost->Evaluate(params, r, nullptr);
  const Eigen::Quaterniond q(e.pose[3], e.pose[0], e.pose[1], e.pose[2]);
  const double z = (q * Eigen::Vector3d(e.point[0], e.point[1], e.point[2])).z() + e.pose[6];
  *behind = z <= 0;
  return r[0] * r[0] + r[1] * r[1];
}

// The robust losses of a solve.
struct Losses {
  explicit Losses(double chi2_threshold) : reprojection(std::sqrt(chi2_threshold)) {}
  ceres::HuberLoss reprojection;
  ceres::HuberLoss prior{2.0};                // ground and range priors: residuals in sigmas
  ceres::HuberLoss anchor{std::sqrt(7.815)};  // box centres, in sigmas: chi-square 95 % of 3 dof
};

struct Block {
  ceres::CostFunction* cost;
  ceres::LossFunction* loss;
  double* pose;
  double* point;  // a map point's or an anchor's
};

// The residual blocks of one solve, in the order either solver adds them: the reprojection edges that are
// not outliers, then the ground and range priors whose pose and point such an edge uses, then the anchors'
// boxes whose pose one uses. Empty when every edge is an outlier.
std::vector<Block> activeBlocks(const Problem& P, bool robust, Losses& losses) {
  std::vector<Block> blocks;
  const auto poseIndex = [&](const double* pose) { return (pose - P.pose_storage.data()) / 7; };
  const auto pointIndex = [&](const double* x) { return (x - P.point_storage.data()) / 3; };
  std::vector<char> pose_used(P.pose_storage.size() / 7, 0), point_used(P.point_storage.size() / 3, 0);
  for (const Edge& e : P.edges) {
    if (e.outlier) continue;
    blocks.push_back({e.cost.get(), robust ? &losses.reprojection : nullptr, e.pose, e.point});
    pose_used[poseIndex(e.pose)] = point_used[pointIndex(e.point)] = 1;
  }
  if (blocks.empty()) return blocks;
  for (auto* edges : {&P.ground_edges, &P.range_edges})
    for (const auto& g : *edges)
      if (pose_used[poseIndex(g.pose)] && point_used[pointIndex(g.point)])
        blocks.push_back({g.cost.get(), &losses.prior, g.pose, g.point});
  for (const auto& a : P.anchor_edges)
    if (pose_used[poseIndex(a.pose)]) blocks.push_back({a.cost.get(), &losses.anchor, a.pose, a.point});
  return blocks;
}

double solveSchurLm(Problem& P, const std::vector<Block>& blocks, int iterations, KeyFrame* origin,
                    double* initial_cost) {
  // Blocks by their place in P's arrays (id order), anchors after the points; a pose without a residual,
  // fixed ones and the origin stay.
  const auto poseIndex = [&](const double* pose) { return static_cast<int>((pose - P.pose_storage.data()) / 7); };
  const int n_points = static_cast<int>(P.point_storage.size() / 3);
  const auto vectorIndex = [&](const double* x) {
    const bool point = x >= P.point_storage.data() && x < P.point_storage.data() + P.point_storage.size();
    return point ? static_cast<int>((x - P.point_storage.data()) / 3)
                 : n_points + static_cast<int>((x - P.anchor_storage.data()) / 3);
  };
  std::vector<char> pose_used(P.pose_storage.size() / 7, 0), fixed(P.pose_storage.size() / 7, 0);
  for (const Block& b : blocks) pose_used[poseIndex(b.pose)] = 1;
  for (KeyFrame* kf : P.fixed) fixed[poseIndex(P.poses[kf])] = 1;
  if (auto it = P.poses.find(origin); it != P.poses.end()) fixed[poseIndex(it->second)] = 1;
  SchurLevenbergMarquardt lm;
  for (size_t k = 0; k < pose_used.size(); ++k) lm.addPose(&P.pose_storage[7 * k], fixed[k] || !pose_used[k]);
  for (int i = 0; i < n_points; ++i) lm.addVector(&P.point_storage[3 * i]);
  for (size_t i = 0; i < P.anchor_ids.size(); ++i) lm.addVector(&P.anchor_storage[3 * i]);
  for (const Block& b : blocks) lm.addResidual(b.cost, b.loss, poseIndex(b.pose), vectorIndex(b.point));
  const SchurLevenbergMarquardt::Summary summary = lm.solve(iterations);
  if (initial_cost) *initial_cost = summary.initial_cost;
  return summary.final_cost;
}

double solve(Problem& P, bool robust, int iterations, double chi2_threshold, bool fix_origin_only, KeyFrame* origin,
             double* initial_cost, BaSolver solver = BaSolver::Ceres) {
  Losses losses(chi2_threshold);
  const std::vector<Block> blocks = activeBlocks(P, robust, losses);
  if (blocks.empty()) return 0;
  // Our solver unless Ceres is asked for or object landmarks take part (their factors are not pose-vector
  // pairs): dense for local windows, block-sparse past SchurLevenbergMarquardt::kMaxDensePoses poses.
  if (solver == BaSolver::SchurLm && !P.objects) return solveSchurLm(P, blocks, iterations, origin, initial_cost);
  ceres::Problem::Options popts;
  popts.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  popts.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  popts.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(popts);
  SE3LeftManifold manifold;
  for (const Block& b : blocks) problem.AddResidualBlock(b.cost, b.loss, b.pose, b.point);
  std::vector<std::unique_ptr<ceres::HuberLoss>> object_losses;
  if (P.objects)
    for (auto& f : P.objects->factors) {
      if (!problem.HasParameterBlock(f.blocks[0])) continue;  // its point or keyframe has no edge left
      object_losses.push_back(std::make_unique<ceres::HuberLoss>(f.huber));
      problem.AddResidualBlock(f.cost.get(), object_losses.back().get(), f.blocks);
    }
  // Points are eliminated first (Schur complement on the cameras).
  auto* ordering = new ceres::ParameterBlockOrdering;
  int n_poses = 0;
  for (auto& [kf, p] : P.poses) {
    if (!problem.HasParameterBlock(p)) continue;
    problem.SetManifold(p, &manifold);
    ordering->AddElementToGroup(p, 1);
    ++n_poses;
  }
  for (auto& [mp, x] : P.positions)
    if (problem.HasParameterBlock(x)) ordering->AddElementToGroup(x, 0);
  // Object nodes in a group of their own after the poses: within a group Ceres orders blocks by address, and
  // the nodes' array is allocated apart from the poses' (on the mapping thread's heap when threaded).
  if (P.objects)
    for (size_t i = 0; i < P.objects->entries.size(); ++i)
      if (problem.HasParameterBlock(P.objects->node(i))) ordering->AddElementToGroup(P.objects->node(i), 2);
  // Anchors in a group of their own, in id order (their array is).
  for (size_t i = 0; i < P.anchor_ids.size(); ++i)
    if (problem.HasParameterBlock(&P.anchor_storage[3 * i])) ordering->AddElementToGroup(&P.anchor_storage[3 * i], 3);
  for (KeyFrame* kf : P.fixed)
    if (problem.HasParameterBlock(P.poses[kf])) problem.SetParameterBlockConstant(P.poses[kf]);
  if (fix_origin_only || origin) {
    auto it = P.poses.find(origin);
    if (it != P.poses.end() && problem.HasParameterBlock(it->second)) problem.SetParameterBlockConstant(it->second);
  }
  ceres::Solver::Options sopts;
  sopts.linear_solver_type = n_poses <= 60 ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
  sopts.linear_solver_ordering.reset(ordering);
  sopts.max_num_iterations = iterations;
  sopts.logging_type = ceres::SILENT;
  sopts.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(sopts, &problem, &summary);
  if (initial_cost) *initial_cost = summary.initial_cost;
  return summary.final_cost;
}

void addEdges(Problem& P, double chi2_threshold, double trusted_weight) {
  (void)chi2_threshold;
  for (MapPoint* mp : P.points) {
    double* x = P.positions[mp];
    for (auto& [kf, idx] : mp->observations) {
      auto it = P.poses.find(kf);
      if (it == P.poses.end() || kf->bad) continue;
      const cv::KeyPoint& kp = kf->keypoint(idx);
      double inv_sigma = kf->pyramid.inv_scale[kp.octave];
      if (mp->trusted) inv_sigma *= std::sqrt(trusted_weight);
      Edge e;
      e.kf = kf;
      e.mp = mp;
      e.idx = idx;
      e.pose = it->second;
      e.point = x;
      e.cost =
          std::make_unique<ReprojectionCost>(Eigen::Vector2d(kp.pt.x, kp.pt.y), inv_sigma,
                                             Intrinsics{kf->camera.fx, kf->camera.fy, kf->camera.cx, kf->camera.cy});
      P.edges.push_back(std::move(e));
    }
  }
}

void writeBack(Problem& P) {
  for (KeyFrame* kf : P.moving) kf->T_cw = paramsToPose(P.poses[kf]);
  if (P.objects) P.objects->writeBack();
  for (MapPoint* mp : P.points) {
    if (mp->bad) continue;
    const double* x = P.positions[mp];
    mp->position = Eigen::Vector3d(x[0], x[1], x[2]);
    mp->updateNormalAndDepth();
  }
}

void addGroundEdges(Problem& P, const GroundPrior& ground, BundleAdjustmentReport* report) {
  const GroundReference& ref = *ground.reference;
  const double sigma = ground.plane.sigma_ratio * ref.height();
  for (KeyFrame* kf : P.moving) {
    const auto plane = fitGroundPlane(*kf, ground.plane, ref.normal(), ground.plane.max_tilt_from_reference_deg);
    if (!plane || std::abs(plane->height / ref.height() - 1.0) > ground.plane.max_height_deviation) continue;
    ++report->ground_keyframes;
    double* pose = P.poses[kf];
    for (MapPoint* mp : plane->inliers) {
      auto it = P.positions.find(mp);
      if (it == P.positions.end()) continue;
      P.ground_edges.push_back(
          {pose, it->second, std::make_unique<GroundHeightCost>(plane->normal_cam, ref.height(), sigma)});
      ++report->ground_residuals;
    }
  }
}

// A metric range per observation, where `range_of` gives one: the point is held at it from the keyframe.
// A range far from the point's now (more than 3 sigma) measures something else (a box's footprint holds
// road and walls behind the car; a LiDAR return beside a keypoint may lie on another surface): no prior.
template <class RangeOf>
int addRangeEdges(Problem& P, RangeOf range_of, double sigma_0, double sigma_per_m) {
  int n = 0;
  for (const Edge& e : P.edges) {
    const float range = range_of(*e.kf->features, e.idx);
    if (!(range > 0)) continue;
    const double sigma = sigma_0 + sigma_per_m * range;
    const Eigen::Vector3d p_cam = e.kf->T_cw * e.mp->position;
    if (std::abs(p_cam.norm() - range) > 3 * sigma) continue;
    P.range_edges.push_back({e.pose, e.point, std::make_unique<ObjectRangeCost>(range, sigma)});
    ++n;
  }
  return n;
}

// The range addRangeEdges takes from a keypoint's LiDAR return (local and global BA).
float lidarRangeOf(const FeatureSet& f, size_t i) { return f.lidarRange(i); }

// One anchor per parked car that a keyframe of the problem saw, if one that moves did and at least two did:
// started at the mean of the boxes' centres in the world, with a BoxCentreCost per box.
void addObjectAnchors(Problem& P, const Map& map, const BundleAdjustmentOptions& options,
                      BundleAdjustmentReport* report) {
  struct Seen {
    double* pose;
    Eigen::Vector3d b_cam, b_world;
    bool moving;
  };
  std::map<int32_t, std::vector<Seen>> seen;  // by object id
  const std::set<const KeyFrame*> moving_kfs(P.moving.begin(), P.moving.end());
  for (const auto& [kf, pose] : P.poses) {
    if (kf->bad) continue;
    const bool moving = moving_kfs.count(kf) > 0;
    for (const ObjectBox& b : kf->features->object_boxes) {
      // Boxes from before the car was called moving belong to where it was parked then.
      if (!b.parked || b.object_id < 0 || kf->id <= map.objects().boxesAfter(b.object_id)) continue;
      const Eigen::Vector3d b_cam = b.T_cam_box.translation();
      seen[b.object_id].push_back({pose, b_cam, kf->T_cw.inverse() * b_cam, moving});
    }
  }
  // A car that is an object node of this BA has its boxes there already (camera-object factors).
  if (P.objects && options.objects.use_boxes)
    for (const objects::ObjectEntry* e : P.objects->entries) seen.erase(static_cast<int32_t>(e->landmark.id));
  for (auto it = seen.begin(); it != seen.end();) {
    const auto& v = it->second;
    const bool useful = v.size() >= 2 && std::any_of(v.begin(), v.end(), [](const Seen& s) { return s.moving; });
    it = useful ? std::next(it) : seen.erase(it);
  }
  P.anchor_storage.assign(3 * seen.size(), 0.0);  // allocated once: the edges point into it
  for (const auto& [id, views] : seen) {
    double* anchor = &P.anchor_storage[3 * P.anchor_ids.size()];
    P.anchor_ids.push_back(id);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Seen& s : views) mean += s.b_world;
    Eigen::Map<Eigen::Vector3d> start(anchor);
    start = mean / static_cast<double>(views.size());
    for (const Seen& s : views) {
      const double sigma = options.object_range_sigma + options.object_range_sigma_per_m * s.b_cam.norm();
      P.anchor_edges.push_back({s.pose, anchor, std::make_unique<BoxCentreCost>(s.b_cam, sigma)});
      ++report->object_anchor_residuals;
    }
  }
}

// The metric terms local and global BA share, in this order: the parked cars' keypoint ranges (with
// object_range_priors), the keypoints' LiDAR ranges, the object landmarks as nodes, one anchor per parked car
// that is not a node.
void addMetricTerms(Problem& P, Map& map, const BundleAdjustmentOptions& options, BundleAdjustmentReport* report) {
  if (options.object_range_sigma > 0 && options.object_range_priors)
    report->object_range_residuals = addRangeEdges(
        P, [](const FeatureSet& f, size_t i) { return f.objectRange(i); }, options.object_range_sigma,
        options.object_range_sigma_per_m);
  if (options.lidar_range_sigma > 0)
    report->lidar_range_residuals =
        addRangeEdges(P, lidarRangeOf, options.lidar_range_sigma, options.lidar_range_sigma_per_m);
  if (options.objects.enabled && map.objects().size() > 0) {
    const std::set<const KeyFrame*> moving(P.moving.begin(), P.moving.end());
    P.objects = objects::buildObjectProblem(map.objects(), P.poses, moving, P.positions, options.objects);
    report->object_nodes = static_cast<int>(P.objects->entries.size());
    report->object_box_factors = P.objects->box_factors;
    report->object_surface_factors = P.objects->surface_factors;
  }
  if (options.object_range_sigma > 0 && options.object_anchors) addObjectAnchors(P, map, options, report);
}

}  // namespace

BundleAdjustmentReport localBundleAdjustment(KeyFrame* kf, Map& map, const BundleAdjustmentOptions& options,
                                             const GroundPrior* ground) {
  BundleAdjustmentReport report;
  Problem P;
  const long stamp = kf->id;
  P.moving.push_back(kf);
  kf->ba_local_for_kf = stamp;
  std::vector<KeyFrame*> neighbours = kf->covisibles();
  if (options.max_local_keyframes > 0 && static_cast<int>(neighbours.size()) > options.max_local_keyframes - 1)
    neighbours.resize(options.max_local_keyframes - 1);
  for (KeyFrame* n : neighbours) {
    if (n->bad) continue;
    n->ba_local_for_kf = stamp;
    P.moving.push_back(n);
  }
  for (KeyFrame* k : P.moving)
    for (MapPoint* mp : k->points) {
      if (!mp || mp->bad || mp->ba_local_for_kf == stamp) continue;
      mp->ba_local_for_kf = stamp;
      P.points.push_back(mp);
    }
  for (MapPoint* mp : P.points)
    for (auto& [k, idx] : mp->observations) {
      if (k->ba_local_for_kf == stamp || k->ba_fixed_for_kf == stamp || k->bad) continue;
      k->ba_fixed_for_kf = stamp;
      P.fixed.push_back(k);
    }
  P.allocate();
  addEdges(P, options.chi2_threshold, options.trusted_weight);
  if (ground && ground->reference && ground->reference->ready()) addGroundEdges(P, *ground, &report);
  addMetricTerms(P, map, options, &report);
  report.keyframes = static_cast<int>(P.moving.size());
  report.fixed_keyframes = static_cast<int>(P.fixed.size());
  report.points = static_cast<int>(P.points.size());
  report.observations = static_cast<int>(P.edges.size());
  if (P.edges.empty()) return report;

  report.final_cost = solve(P, true, options.robust_iterations, options.chi2_threshold, false, map.origin(),
                            &report.initial_cost, options.solver);
  if (options.between_passes) options.between_passes();
  for (Edge& e : P.edges) {
    bool behind = false;
    e.outlier = chi2(e, &behind) > options.chi2_threshold || behind;
  }
  if (!(options.stop_early && options.stop_early->load())) {
    report.final_cost = solve(P, false, options.refine_iterations, options.chi2_threshold, false, map.origin(), nullptr,
                              options.solver);
    if (options.between_passes) options.between_passes();
  } else {
    report.stopped_early = true;
  }
  for (Edge& e : P.edges) {
    bool behind = false;
    if (chi2(e, &behind) > options.chi2_threshold || behind) {
      if (e.mp->bad) continue;
      if (e.kf->points[e.idx] == e.mp) e.kf->erasePoint(e.idx);
      e.mp->eraseObservation(e.kf);
      ++report.outliers_removed;
    }
  }
  writeBack(P);
  return report;
}

BundleAdjustmentReport globalBundleAdjustment(Map& map, int iterations, const BundleAdjustmentOptions& options) {
  BundleAdjustmentReport report;
  Problem P;
  for (KeyFrame* kf : map.keyframes()) P.moving.push_back(kf);
  for (MapPoint* mp : map.points()) P.points.push_back(mp);
  P.allocate();
  addEdges(P, options.chi2_threshold, 1.0);
  addMetricTerms(P, map, options, &report);
  report.keyframes = static_cast<int>(P.moving.size());
  report.points = static_cast<int>(P.points.size());
  report.observations = static_cast<int>(P.edges.size());
  if (P.edges.empty()) return report;
  report.final_cost =
      solve(P, true, iterations, options.chi2_threshold, true, map.origin(), &report.initial_cost, options.solver);
  writeBack(P);
  return report;
}

}  // namespace beslam::orb::optimize
