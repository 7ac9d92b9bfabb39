#include "mapping/local_mapper.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "ground/ground_plane.hpp"
#include "init/two_view.hpp"
#include "map/camera_model.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "mapping/map_gate.hpp"
#include "matching/matcher.hpp"
#include "stage_clock.hpp"

namespace beslam::orb {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

// Fusion: with the best covisible keyframes and, of each, its best ones (ORB-SLAM2's 20 and 5).
constexpr int kFuseNeighbours = 20, kFuseSecondOrder = 5;
// Once settled, a local scale correction larger than this share is not trusted (ScaleOptions::metric_correction_min).
constexpr double kMetricCorrectionMax = 0.05;

// Local BA as the options ask for it, before the metric terms (metricTerms).
optimize::BundleAdjustmentOptions localBundleAdjustmentOptions(const MappingOptions& m, const ScaleOptions& scale,
                                                               const ObjectLandmarkOptions& o,
                                                               double static_object_weight) {
  optimize::BundleAdjustmentOptions ba;
  ba.robust_iterations = m.local_ba_iterations_robust;
  ba.refine_iterations = m.local_ba_iterations_refine;
  ba.max_local_keyframes = m.local_ba_max_keyframes;
  ba.solver = optimize::baSolver(m.local_ba_solver);
  ba.trusted_weight = static_object_weight;
  ba.objects.enabled = o.mode != ObjectLandmarkMode::Off;
  ba.objects.pose_weight = o.pose_weight;
  ba.objects.surface_weight = o.surface_weight;
  ba.objects.box_sigma = o.box_sigma;
  ba.objects.box_sigma_per_m = o.box_sigma_per_m;
  ba.objects.yaw_sigma = o.yaw_sigma_deg * M_PI / 180.0;
  ba.objects.surface_sigma = o.surface_sigma;
  ba.objects.surface_gate = o.surface_gate;
  ba.object_anchors = scale.object_scale_hold == ObjectScaleHold::Anchors;
  ba.object_range_priors = scale.object_scale_hold == ObjectScaleHold::Ranges;
  return ba;
}

// The ground fits' options: the ground prior's, also on with metric scale.
GroundPlaneOptions groundPlaneOptions(const ScaleOptions& scale) {
  GroundPlaneOptions g;
  g.enabled = scale.ground_prior || scale.metric_scale;
  // A metric map knows the camera height itself, which a car's load and suspension change by a few percent:
  // a plane 10 % off it is not the road under the camera (a kerb, a wall's foot, a bare road's stray points).
  if (scale.metric_scale) g.max_height_deviation = 0.1;
  g.sigma_ratio = scale.ground_prior_sigma;
  g.reference_keyframes = scale.ground_reference_keyframes;
  g.min_inliers = scale.ground_min_inliers;
  g.pool_keyframes = scale.ground_pool_keyframes;
  return g;
}

}  // namespace

LocalMapper::LocalMapper(Map& map, const Camera& camera, const ScalePyramid& pyramid, const MappingOptions& mapping,
                         const ScaleOptions& scale, const ObjectLandmarkOptions& objects, double static_object_weight)
    : map_(map),
      camera_(camera),
      pyramid_(pyramid),
      mapping_(mapping),
      scale_(scale),
      ba_(localBundleAdjustmentOptions(mapping, scale, objects, static_object_weight)),
      ground_(groundPlaneOptions(scale)),
      metric_camera_height_(scale.metric_scale ? scale.camera_height : 0),
      object_range_sigma_(scale.metric_scale && scale.object_scale ? scale.object_range_sigma : 0),
      lidar_range_sigma_(scale.metric_scale && scale.lidar_scale ? scale.lidar_range_sigma : 0),
      ground_reference_(makeGroundReference()),
      object_reference_(ground_.reference_keyframes, scale.metric_max_spread),
      lidar_reference_(scale.lidar_reference_keyframes, scale.metric_max_spread) {}

void LocalMapper::yieldPoint() {
  if (gate_) gate_->yieldToTracker();
}

optimize::BundleAdjustmentOptions LocalMapper::metricTerms() const {
  optimize::BundleAdjustmentOptions ba = ba_;
  if (metric_) {  // the boxes are metric: so is the map now
    ba.object_range_sigma = object_range_sigma_;
    ba.object_range_sigma_per_m = scale_.object_range_sigma_per_m;
  }
  if (metric_ && lidar_scaled_) {  // and the scan's ranges, once they agree with the map's unit
    ba.lidar_range_sigma = lidar_range_sigma_;
    ba.lidar_range_sigma_per_m = scale_.lidar_range_sigma_per_m;
  }
  // Object landmarks are metric (boxes, shapes): they enter only a metric map.
  ba.objects.enabled = ba_.objects.enabled && metric_;
  return ba;
}

void LocalMapper::processKeyFrame(KeyFrame* kf, bool run_ba) {
  timings_.clear();
  auto t0 = Clock::now();
  registerKeyFrame(kf);
  timings_.emplace_back("map_register", msSince(t0));
  if (!run_ba) return;
  yieldPoint();
  t0 = Clock::now();
  cullRecentPoints(kf);
  timings_.emplace_back("map_point_culling", msSince(t0));
  t0 = Clock::now();
  last_new_points_ = createNewPoints(kf);
  timings_.emplace_back("map_triangulate", msSince(t0));
  int ranged_points = 0;
  if (scale_.lidar_points && lidar_scaled_) {
    t0 = Clock::now();
    ranged_points = createRangedPoints(kf);
    ranged_points_ += ranged_points;
    timings_.emplace_back("map_lidar_points", msSince(t0));
  }
  yieldPoint();
  t0 = Clock::now();
  fuseWithNeighbours(kf);
  timings_.emplace_back("map_fuse", msSince(t0));
  yieldPoint();
  t0 = Clock::now();
  if (map_.numKeyFrames() > 2) {
    optimize::GroundPrior ground{ground_, &ground_reference_};
    optimize::BundleAdjustmentOptions ba = metricTerms();
    // Once the parked cars' boxes gave the scale, their range priors hold it; the ground prior would pull it
    // towards the road fits, whose biases (bare roads, kerbs) fight the direct measurement.
    const bool ground_prior = ground_.enabled && !object_scaled_ && !lidar_scaled_;
    if (gate_) ba.between_passes = [this] { yieldPoint(); };
    if (stop_ba_) ba.stop_early = stop_ba_;
    last_ba_ = optimize::localBundleAdjustment(kf, map_, ba, ground_prior ? &ground : nullptr);
    if (lidar_range_sigma_ > 0 && metric_camera_height_ > 0 && !lidar_scaled_ && !pending_scale_)
      measureScaleByLidar(kf);
    if (object_range_sigma_ > 0 && metric_camera_height_ > 0 && !metric_ && !pending_scale_) {
      if (const auto s = objectScale(*kf)) object_reference_.add(*s);
      if (object_reference_.ready()) pending_scale_ = currentObjectScale(kf).value_or(object_reference_.height());
    }
    if (ground_.enabled && !ground_reference_.ready()) {
      if (const auto plane = fitGroundPlane(*kf, ground_, Eigen::Vector3d::UnitY(), ground_.max_tilt_deg))
        ground_reference_.add(*plane);
      if (metric_) ground_reference_.setHeight(metric_camera_height_);  // metric by the objects first
      if (ground_reference_.ready() && metric_camera_height_ > 0 && !metric_ && !pending_scale_)
        pending_scale_ = metric_camera_height_ / currentGroundHeight(kf);
    }
    if (metric_ && !object_scaled_ && !lidar_scaled_ && scale_.metric_correction_min > 0) keepScale(kf);
  }
  timings_.emplace_back("map_local_ba", msSince(t0));
  yieldPoint();
  t0 = Clock::now();
  int culled = 0;
  if (mapping_.keyframe_culling) culled = cullKeyFrames(kf);
  timings_.emplace_back("map_kf_culling", msSince(t0));
  if (std::getenv("BESLAM_ORB_DEBUG")) {  // one line per keyframe for developers
    if (const auto plane = fitGroundPlane(*kf, ground_, Eigen::Vector3d::UnitY(), ground_.max_tilt_deg))
      std::fprintf(stderr, "  kf %ld frame %ld: ground fit h %.4f (%zu inliers)\n", kf->id,
                   static_cast<long>(kf->frame_index), plane->height, plane->inliers.size());
    int obs_hist[6] = {0, 0, 0, 0, 0, 0};
    for (MapPoint* mp : kf->validPoints()) ++obs_hist[std::min(mp->numObservations(), 5)];
    std::fprintf(stderr,
                 "  kf %ld frame %ld: points %zu (obs 2:%d 3:%d 4:%d 5+:%d) new %d covis %zu recent %zu culled %d "
                 "map %zu/%zu ground %d kfs %d res (h_ref %.4f) ba outliers %d anchors %d lidar %d (unit %.4f) "
                 "lidar points %d\n",
                 kf->id, static_cast<long>(kf->frame_index), kf->validPoints().size(), obs_hist[2], obs_hist[3],
                 obs_hist[4], obs_hist[5], last_new_points_, kf->covisibles().size(), recent_.size(), culled,
                 map_.numKeyFrames(), map_.points().size(), last_ba_.ground_keyframes, last_ba_.ground_residuals,
                 groundReferenceHeight(), last_ba_.outliers_removed, last_ba_.object_anchor_residuals,
                 last_ba_.lidar_range_residuals, lidarScale(*kf).value_or(0.0), ranged_points);
  }
}

void LocalMapper::keepScale(KeyFrame* kf) {
  const double H = metric_camera_height_;
  const auto plane = fitGroundPlane(*kf, ground_, ground_reference_.normal(), ground_.max_tilt_from_reference_deg);
  if (!plane || std::abs(plane->height / H - 1.0) > ground_.max_height_deviation) return;
  scale_fits_.emplace_back(kf->id, plane->height);
  const size_t K = static_cast<size_t>(ground_.reference_keyframes);
  if (scale_fits_.size() > K) scale_fits_.erase(scale_fits_.begin());
  if (scale_fits_.size() < K) return;
  std::vector<double> ratios;
  for (const auto& f : scale_fits_) ratios.push_back(H / f.second);
  const double r = median(ratios);
  // Standard error of the median of K fits, from their median absolute deviation (normal: 1.4826 MAD).
  const double se = 1.4826 * medianAbsoluteDeviation(ratios, r) * 1.2533 / std::sqrt(static_cast<double>(K));
  if (std::abs(r - 1.0) <= std::max(scale_.metric_correction_min, 2.0 * se)) return;
  // While the metric map is young its whole extent shares the first estimate's error: the whole map is
  // corrected. Later, drift is local and slow: the map from the oldest of the fits on is corrected, and only
  // by a few percent (a larger step over a few keyframes is the fits' own bias: a junction, a bare road).
  const bool settling = kf->id - metric_since_kf_ < 3 * static_cast<long>(K);
  if (!settling && std::abs(r - 1.0) > kMetricCorrectionMax) {
    scale_fits_.clear();
    return;
  }
  pending_correction_ = ScaleCorrection{settling ? 0 : scale_fits_.front().first, r};
  scale_fits_.clear();
}

namespace {

// A keyframe's metres per map unit from metric ranges of its keypoints (`range_of`: 0 where there is none):
// the median of range over the matched map point's distance, from at least min_points of them.
template <class RangeOf>
std::optional<double> rangeScale(const KeyFrame& kf, RangeOf range_of, int min_points) {
  std::vector<double> ratios;
  for (size_t i = 0; i < kf.points.size(); ++i) {
    const MapPoint* mp = kf.points[i];
    const float range = range_of(*kf.features, i);
    if (!mp || mp->bad || !(range > 0)) continue;
    const double d = (kf.T_cw * mp->position).norm();
    if (d > 0) ratios.push_back(range / d);
  }
  if (static_cast<int>(ratios.size()) < min_points) return std::nullopt;
  return median(std::move(ratios));
}

}  // namespace

std::optional<double> LocalMapper::objectScale(const KeyFrame& kf) const {
  // A few points on a car say little: 8 at least.
  return rangeScale(
      kf, [](const FeatureSet& f, size_t i) { return f.objectRange(i); }, 8);
}

std::optional<double> LocalMapper::currentObjectScale(KeyFrame* kf) const {
  // As for the ground: the map as it is now, over the keyframe and its best covisible keyframes.
  std::vector<double> scales;
  if (const auto s = objectScale(*kf)) scales.push_back(*s);
  for (KeyFrame* k : kf->bestCovisibles(ground_.reference_keyframes * 2))
    if (!k->bad)
      if (const auto s = objectScale(*k)) scales.push_back(*s);
  if (static_cast<int>(scales.size()) < ground_.reference_keyframes) return std::nullopt;
  return median(std::move(scales));
}

std::optional<double> LocalMapper::lidarScale(const KeyFrame& kf) const {
  return rangeScale(
      kf, [](const FeatureSet& f, size_t i) { return f.lidarRange(i); }, scale_.lidar_min_points);
}

void LocalMapper::measureScaleByLidar(KeyFrame* kf) {
  // The two-view map's first keyframes are where the map's unit is set: no settling time is needed here,
  // since the scan measures each keyframe's unit directly (a median over its keypoints: edges, returns the
  // camera does not see and moving points are outvoted).
  const auto s_kf = lidarScale(*kf);
  if (!s_kf) return;
  lidar_reference_.add(*s_kf);
  if (!lidar_reference_.ready()) return;
  // As for the road and the boxes: the factor of the map as it is now, over the keyframe and its best
  // covisible keyframes (the reference's own samples were taken before later local BAs moved the map).
  std::vector<double> scales{*s_kf};
  for (KeyFrame* k : kf->bestCovisibles(scale_.lidar_reference_keyframes * 2))
    if (!k->bad)
      if (const auto s = lidarScale(*k)) scales.push_back(*s);
  const double s = median(std::move(scales));
  if (!metric_) {
    pending_scale_ = s;
  } else if (std::abs(s - 1.0) > 1e-3) {  // metric by the road or the boxes already: the whole map follows
    pending_correction_ = ScaleCorrection{0, s};
  }
  lidar_scaled_ = true;
  scale_fits_.clear();
}

std::vector<std::pair<KeyFrame*, double>> LocalMapper::keyFrameGroundHeights() const {
  std::vector<std::pair<KeyFrame*, double>> out;
  for (KeyFrame* k : map_.keyframes())
    if (const auto plane = fitGroundPlane(*k, ground_, ground_reference_.normal(), ground_.max_tilt_from_reference_deg))
      out.emplace_back(k, plane->height);
  return out;
}

double LocalMapper::currentGroundHeight(KeyFrame* kf) const {
  // The fits behind the reference were made when each keyframe was new; local BA has moved the map since.
  // The scale that matters is the map's as it is now: refit the newest keyframes' planes.
  std::vector<double> heights;
  for (KeyFrame* k : kf->bestCovisibles(ground_.reference_keyframes * 2)) {
    if (k->bad) continue;
    if (const auto plane = fitGroundPlane(*k, ground_, ground_reference_.normal(), ground_.max_tilt_from_reference_deg))
      heights.push_back(plane->height);
  }
  if (const auto plane = fitGroundPlane(*kf, ground_, ground_reference_.normal(), ground_.max_tilt_from_reference_deg))
    heights.push_back(plane->height);
  if (static_cast<int>(heights.size()) < ground_.reference_keyframes) return ground_reference_.height();
  return median(std::move(heights));
}

void LocalMapper::registerKeyFrame(KeyFrame* kf) {
  for (size_t i = 0; i < kf->points.size(); ++i) {
    MapPoint* mp = kf->points[i];
    if (!mp) continue;
    if (mp->bad) {
      kf->erasePoint(i);
      continue;
    }
    if (!mp->isIn(kf)) {
      mp->addObservation(kf, i);
      mp->updateNormalAndDepth();
      mp->computeDistinctiveDescriptor();
    }
  }
  kf->updateConnections();
}

void LocalMapper::forgetCulled() {
  recent_.remove_if([](const MapPoint* mp) { return mp->bad; });
}

void LocalMapper::cullRecentPoints(KeyFrame* kf) {
  for (auto it = recent_.begin(); it != recent_.end();) {
    MapPoint* mp = *it;
    // ORB-SLAM2 counts an observation with a depth twice: a point made from a LiDAR range starts with one.
    const int th_obs = mp->from_range ? 1 : 2;
    const long age = kf->id - mp->first_keyframe_id;
    if (mp->bad) {
      it = recent_.erase(it);
    } else if (!mp->trusted && mp->foundRatio() < 0.25) {
      mp->setBad();
      it = recent_.erase(it);
    } else if (!mp->trusted && age >= 2 && mp->numObservations() <= th_obs) {
      mp->setBad();
      it = recent_.erase(it);
    } else if (age >= 3) {
      it = recent_.erase(it);
    } else {
      ++it;
    }
  }
}

int LocalMapper::createNewPoints(KeyFrame* kf) {
  const auto neighbours = kf->bestCovisibles(mapping_.triangulation_neighbours);
  const Eigen::Matrix3d K = intrinsics(camera_), Kinv = K.inverse();
  const Eigen::Isometry3d T1 = kf->T_cw;
  const Eigen::Vector3d O1 = kf->centre();
  const Eigen::Matrix3d R1wc = T1.linear().transpose();
  const double ratio_factor = 1.5 * pyramid_.factor;
  int created = 0;
  std::vector<std::pair<int, int>> matches;
  for (KeyFrame* kf2 : neighbours) {
    yieldPoint();  // each neighbour's search and triangulation is a step of its own
    if (kf2->bad) continue;
    const Eigen::Vector3d O2 = kf2->centre();
    const double baseline = (O2 - O1).norm();
    const double median2 = kf2->medianDepth(2);
    if (median2 <= 0 || baseline / median2 < 0.01) continue;
    const Eigen::Isometry3d T2 = kf2->T_cw;
    const Eigen::Isometry3d T21 = T2 * T1.inverse();
    const Eigen::Matrix3d F21 = Kinv.transpose() * skew(T21.translation()) * T21.linear() * Kinv;
    matching::searchForTriangulation(kf, kf2, F21, matches, static_cast<float>(mapping_.triangulation_ratio),
                                     mapping_.triangulation_check_orientation, mapping_.triangulation_bow);
    Eigen::Matrix<double, 3, 4> P1, P2;
    P1 << T1.linear(), T1.translation();
    P2 << T2.linear(), T2.translation();
    const Eigen::Matrix3d R2wc = T2.linear().transpose();
    for (auto [i1, i2] : matches) {
      if (kf->points[i1] || kf2->points[i2]) continue;
      const cv::KeyPoint& kp1 = kf->keypoint(i1);
      const cv::KeyPoint& kp2 = kf2->keypoint(i2);
      const Eigen::Vector3d xn1 = unproject(camera_, kp1.pt.x, kp1.pt.y);
      const Eigen::Vector3d xn2 = unproject(camera_, kp2.pt.x, kp2.pt.y);
      const Eigen::Vector3d ray1 = R1wc * xn1, ray2 = R2wc * xn2;
      const double cos_rays = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
      if (cos_rays <= 0 || cos_rays >= mapping_.triangulation_max_cos_parallax) continue;
      const Eigen::Vector3d X = TwoViewInitializer::triangulate(xn1.head<2>(), xn2.head<2>(), P1, P2);
      if (!X.allFinite()) continue;
      const Eigen::Vector3d x1c = T1 * X, x2c = T2 * X;
      if (x1c.z() <= 0 || x2c.z() <= 0) continue;
      const Eigen::Vector2d u1 = project(camera_, x1c), u2 = project(camera_, x2c);
      if ((u1 - Eigen::Vector2d(kp1.pt.x, kp1.pt.y)).squaredNorm() > 5.991 * pyramid_.sigma2[kp1.octave]) continue;
      if ((u2 - Eigen::Vector2d(kp2.pt.x, kp2.pt.y)).squaredNorm() > 5.991 * pyramid_.sigma2[kp2.octave]) continue;
      const double d1 = (X - O1).norm(), d2 = (X - O2).norm();
      if (d1 <= 0 || d2 <= 0) continue;
      const double ratio_dist = d2 / d1;
      const double ratio_octave = pyramid_.scale[kp1.octave] / pyramid_.scale[kp2.octave];
      if (ratio_dist * ratio_factor < ratio_octave || ratio_dist > ratio_octave * ratio_factor) continue;

      MapPoint* mp = map_.createMapPoint(X, kf);
      mp->addObservation(kf, i1);
      mp->addObservation(kf2, i2);
      kf->addPoint(mp, i1);
      kf2->addPoint(mp, i2);
      mp->trusted = kf->features->onStaticObject(i1) || kf2->features->onStaticObject(i2);
      mp->object_id = kf->features->onStaticObject(i1) ? kf->features->objectId(i1) : kf2->features->objectId(i2);
      const cv::Vec3b c = kf->features->colours[i1];
      mp->completeNewPoint({c[0], c[1], c[2]});
      recent_.push_back(mp);
      ++created;
    }
  }
  return created;
}

int LocalMapper::createRangedPoints(KeyFrame* kf) {
  // As ORB-SLAM2's stereo and RGB-D keyframes make points from their depths, after triangulation here so
  // that the points two views agree on come first: the scan fills in what triangulation left (too little
  // parallax, a thin stretch). Each point sits at its keypoint's LiDAR range along the keypoint's own ray
  // (scale/lidar_range.hpp: none across an edge); the range holds it in local BA from its first
  // observation on, and it is culled like a triangulated point.
  const Eigen::Isometry3d T_world_cam = kf->T_cw.inverse();
  const FeatureSet& f = *kf->features;
  std::vector<std::pair<float, size_t>> by_range;
  for (size_t i = 0; i < kf->points.size(); ++i)
    if (f.lidarRange(i) > 0 && !kf->points[i]) by_range.emplace_back(f.lidarRange(i), i);
  const size_t n = std::min(by_range.size(), static_cast<size_t>(scale_.lidar_points_per_keyframe));
  std::partial_sort(by_range.begin(), by_range.begin() + static_cast<std::ptrdiff_t>(n), by_range.end());
  int created = 0;
  for (size_t k = 0; k < n; ++k) {
    const auto [range, i] = by_range[k];
    const cv::KeyPoint& kp = f.keypoints[i];
    const Eigen::Vector3d p_cam = unproject(camera_, kp.pt.x, kp.pt.y).normalized() * static_cast<double>(range);
    MapPoint* mp = map_.createMapPoint(T_world_cam * p_cam, kf);
    mp->addObservation(kf, i);
    kf->addPoint(mp, i);
    mp->from_range = true;
    mp->trusted = f.onStaticObject(i);
    mp->object_id = f.objectId(i);
    const cv::Vec3b c = f.colours[i];
    mp->completeNewPoint({c[0], c[1], c[2]});
    recent_.push_back(mp);
    ++created;
  }
  return created;
}

void LocalMapper::fuseWithNeighbours(KeyFrame* kf) {
  std::vector<KeyFrame*> targets;
  for (KeyFrame* n : kf->bestCovisibles(kFuseNeighbours)) {
    if (n->bad || n == kf || n->fuse_target_for_kf == kf->id) continue;
    n->fuse_target_for_kf = kf->id;
    targets.push_back(n);
  }
  const size_t first_order = targets.size();
  for (size_t i = 0; i < first_order; ++i)
    for (KeyFrame* n2 : targets[i]->bestCovisibles(kFuseSecondOrder)) {
      if (n2->bad || n2 == kf || n2->fuse_target_for_kf == kf->id) continue;
      n2->fuse_target_for_kf = kf->id;
      targets.push_back(n2);
    }
  for (KeyFrame* t : targets) matching::fuse(t, kf->validPoints());
  std::vector<MapPoint*> candidates;
  for (KeyFrame* t : targets)
    for (MapPoint* mp : t->points) {
      if (!mp || mp->bad || mp->fuse_candidate_for_kf == kf->id) continue;
      mp->fuse_candidate_for_kf = kf->id;
      candidates.push_back(mp);
    }
  matching::fuse(kf, candidates);
  for (MapPoint* mp : kf->validPoints()) {
    mp->computeDistinctiveDescriptor();
    mp->updateNormalAndDepth();
  }
  kf->updateConnections();
}

int LocalMapper::cullKeyFrames(KeyFrame* kf) {
  const int th_obs = 3;
  int culled = 0;
  for (KeyFrame* k : kf->covisibles()) {
    if (k->bad || k == map_.origin() || k == kf) continue;
    int n_points = 0, redundant = 0;
    for (size_t i = 0; i < k->points.size(); ++i) {
      MapPoint* mp = k->points[i];
      if (!mp || mp->bad) continue;
      ++n_points;
      if (mp->numObservations() <= th_obs) continue;
      const int level = k->keypoint(i).octave;
      int n_obs = 0;
      for (auto& [other, idx] : mp->observations) {
        if (other == k) continue;
        if (other->keypoint(idx).octave <= level + 1 && ++n_obs >= th_obs) break;
      }
      if (n_obs >= th_obs) ++redundant;
    }
    if (redundant > 0.9 * n_points) {
      k->setBad();
      ++culled;
    }
  }
  return culled;
}

}  // namespace beslam::orb
