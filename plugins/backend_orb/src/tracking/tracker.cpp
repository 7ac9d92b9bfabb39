#include "tracking/tracker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "map/camera_model.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "map_io/localise_in_map.hpp"
#include "matching/matcher.hpp"
#include "objects/object_layout.hpp"
#include "optimize/bundle_adjustment.hpp"
#include "optimize/pnp_pose.hpp"
#include "optimize/pose_optimizer.hpp"
#include "place/keyframe_database.hpp"
#include "stage_clock.hpp"

namespace beslam::orb {
namespace {

constexpr int kBowDirectLevelsUp = 4;  // direct index: features grouped 4 levels above the words (ORB-SLAM2)

// The map point of slot i, or null; a bad point is dropped from the slot first.
MapPoint* goodPoint(std::vector<MapPoint*>& points, size_t i) {
  if (points[i] && points[i]->bad) points[i] = nullptr;
  return points[i];
}

}  // namespace

Tracker::Tracker(const Camera& camera, const TrackerOptions& options, const ScalePyramid& pyramid, Map& map,
                 KeyFrameSink sink, std::function<void()> on_reset, const place::Vocabulary* vocabulary,
                 KeyFrameDatabase* database)
    : camera_(camera),
      options_(options),
      pyramid_(pyramid),
      map_(map),
      sink_(std::move(sink)),
      on_reset_(std::move(on_reset)),
      vocabulary_(vocabulary),
      database_(database) {}

void Tracker::computeBow(Frame& f) const {
  if (!vocabulary_ || f.has_bow || !f.features) return;
  vocabulary_->transform(f.features->descriptors, f.bow, &f.feature_vector, kBowDirectLevelsUp);
  f.has_bow = true;
}

void Tracker::mapLoaded() {
  state_ = TrackingState::Lost;
  map_loaded_ = true;
  if (!vocabulary_ || !database_) return;
  for (KeyFrame* kf : map_.keyframes()) {  // a map file keeps descriptors, not words: this vocabulary's words
    if (kf->bad || !kf->features) continue;
    vocabulary_->transform(kf->features->descriptors, kf->bow, &kf->feature_vector, kBowDirectLevelsUp);
    database_->add(kf);
  }
}

std::optional<Eigen::Isometry3d> Tracker::predictPose() const {
  if (state_ != TrackingState::Ok || !velocity_ || !last_.has_pose) return std::nullopt;
  return ((*velocity_) * last_.T_cw).inverse();
}

std::optional<Eigen::Isometry3d> Tracker::lastPoseInMap() const {
  if (state_ != TrackingState::Ok || !last_.has_pose || records_.empty() || records_.back().index != last_.index)
    return std::nullopt;
  const FrameRecord& rec = records_.back();
  Eigen::Isometry3d T_c_ref = rec.T_c_ref;
  KeyFrame* ref = rec.reference;
  while (ref && ref->bad && ref->parent) {
    T_c_ref = T_c_ref * ref->T_cp;
    ref = ref->parent;
  }
  if (!ref) return std::nullopt;
  return T_c_ref * ref->T_cw;
}

TrackResult Tracker::track(std::shared_ptr<const FeatureSet> features, double timestamp, int64_t index) {
  TrackResult result;
  current_ = Frame(index, timestamp, std::move(features));
  if (state_ == TrackingState::NotInitialized) {
    if (options_.localisation_only) return result;  // no map to localise in; making one would change it
    auto t0 = Clock::now();
    initialise(result);
    result.stage_ms.emplace_back("initialise", msSince(t0));
    result.state = state_;
    if (state_ == TrackingState::Ok) {
      result.T_world_cam = current_.T_cw.inverse();
      result.is_keyframe = true;
      result.keyframe_id = last_kf_->id;
      result.tracked_points = inliers_;
    }
    return result;
  }

  auto t0 = Clock::now();
  bool ok = false;
  // Points replaced by fusion since the last frame.
  for (MapPoint*& mp : last_.points)
    if (mp && mp->replaced_by) mp = mp->latest()->bad ? nullptr : mp->latest();
  // The last frame's pose re-anchored to its reference keyframe, which local BA may have moved since.
  if (const auto T_cw = lastPoseInMap()) last_.T_cw = *T_cw;
  if (state_ == TrackingState::Ok) {
    if (!velocity_ || index < last_reloc_frame_ + 2) {
      ok = trackReferenceKeyFrame();
    } else {
      ok = trackWithMotionModel();
      if (!ok) ok = trackReferenceKeyFrame();
    }
  } else if (options_.tracking.relocalisation) {
    ok = relocalise();
    result.relocalised = ok;  // counted once local-map tracking confirms it
  }
  result.stage_ms.emplace_back("track_frame", msSince(t0));
  current_.reference = validReference();
  t0 = Clock::now();
  if (ok) ok = trackLocalMap();
  result.stage_ms.emplace_back("track_local_map", msSince(t0));
  result.relocalised = result.relocalised && ok;
  if (result.relocalised) ++relocalisations_;

  if (ok) {
    state_ = TrackingState::Ok;
    velocity_ = last_.has_pose ? std::optional<Eigen::Isometry3d>(current_.T_cw * last_.T_cw.inverse()) : std::nullopt;
    last_good_pose_ = current_.T_cw;
    t0 = Clock::now();
    if (!options_.localisation_only && needNewKeyFrame()) {
      createKeyFrame();
      result.is_keyframe = true;
      result.keyframe_id = last_kf_->id;
    }
    result.stage_ms.emplace_back("keyframe_decision", msSince(t0));
    for (size_t i = 0; i < current_.size(); ++i)
      if (current_.outlier[i]) {
        current_.points[i] = nullptr;
        current_.outlier[i] = false;
      }
    KeyFrame* ref = validReference();
    current_.reference = ref;
    records_.push_back({index, timestamp, ref, current_.T_cw * ref->T_cw.inverse(), current_.T_cw});
    result.T_world_cam = current_.T_cw.inverse();
    result.tracked_points = inliers_;
  } else {
    if (std::getenv("BESLAM_ORB_DEBUG"))  // developers: why a frame was lost
      std::fprintf(stderr, "frame %ld: lost (local-map inliers %d, keyframes %zu)\n", static_cast<long>(index),
                   inliers_, map_.numKeyFrames());
    state_ = TrackingState::Lost;
    velocity_.reset();
    current_.has_pose = false;
    if (!options_.localisation_only && !map_loaded_ &&
        static_cast<int>(map_.numKeyFrames()) <= options_.tracking.lost_reset_max_keyframes) {
      reset();
      result.state = state_;
      return result;
    }
  }
  result.state = state_;
  last_ = current_;
  return result;
}

KeyFrame* Tracker::validReference() {
  KeyFrame* ref = reference_kf_;
  while (ref && ref->bad) ref = ref->parent;
  if (!ref) ref = last_kf_;
  while (ref && ref->bad) ref = ref->parent;
  if (!ref) ref = map_.origin();
  reference_kf_ = ref;
  return ref;
}

// ---------------------------------------------------------------- initialisation

void Tracker::initialise(TrackResult& result) {
  (void)result;
  if (!init_active_) {
    if (current_.size() > 100) {
      init_frame_ = current_;
      init_between_.clear();
      prev_matched_.clear();
      for (const auto& kp : current_.features->keypoints) prev_matched_.push_back(kp.pt);
      init_active_ = true;
    }
    return;
  }
  if (current_.size() <= 100) {
    init_active_ = false;
    return;
  }
  std::vector<int> matches12;
  const int n = matching::searchForInitialization(*init_frame_.features, *current_.features, prev_matched_, matches12,
                                                  100, 0.9f, options_.init.match_max_level);
  if (n < 100) {
    init_active_ = false;
    return;
  }
  TwoViewOptions tv;
  tv.iterations = options_.init.ransac_iterations;
  tv.min_parallax_deg = options_.init.min_parallax_deg;
  tv.seed = options_.seed + static_cast<uint64_t>(current_.index);
  TwoViewInitializer initializer(camera_, tv);
  TwoViewResult r;
  if (!initializer.reconstruct(init_frame_.features->keypoints, current_.features->keypoints, matches12, r)) {
    if (init_between_.size() < 30) init_between_.push_back(current_);
    return;
  }
  for (size_t i = 0; i < matches12.size(); ++i)
    if (matches12[i] >= 0 && !r.triangulated[i]) matches12[i] = -1;
  if (!createInitialMap(matches12, r)) reset();
}

bool Tracker::createInitialMap(const std::vector<int>& matches12, const TwoViewResult& r) {
  init_frame_.T_cw = Eigen::Isometry3d::Identity();
  init_frame_.has_pose = true;
  current_.T_cw = Eigen::Isometry3d::Identity();
  current_.T_cw.linear() = r.R21;
  current_.T_cw.translation() = r.t21;
  current_.has_pose = true;
  current_.clearMatches();
  init_frame_.clearMatches();
  computeBow(init_frame_);
  computeBow(current_);
  KeyFrame* kf_ini = map_.createKeyFrame(init_frame_, camera_, pyramid_);
  KeyFrame* kf_cur = map_.createKeyFrame(current_, camera_, pyramid_);
  for (size_t i = 0; i < matches12.size(); ++i) {
    const int j = matches12[i];
    if (j < 0) continue;
    MapPoint* mp = map_.createMapPoint(r.points[i], kf_cur);
    kf_ini->addPoint(mp, i);
    kf_cur->addPoint(mp, j);
    mp->addObservation(kf_ini, i);
    mp->addObservation(kf_cur, j);
    mp->trusted = kf_ini->features->onStaticObject(i);
    mp->object_id = kf_ini->features->objectId(i);
    const cv::Vec3b c = kf_ini->features->colours[i];
    mp->completeNewPoint({c[0], c[1], c[2]});
    current_.points[j] = mp;
  }
  kf_ini->updateConnections();
  kf_cur->updateConnections();
  optimize::globalBundleAdjustment(map_, 20, optimize::plainOptions(optimize::BaSolver::Ceres));

  const double median = kf_ini->medianDepth(2);
  if (median <= 0 || kf_cur->trackedPoints(1) < 100) return false;
  const double inv = 1.0 / median;
  kf_cur->T_cw.translation() *= inv;
  for (MapPoint* mp : kf_ini->points)
    if (mp) mp->position *= inv;
  for (MapPoint* mp : kf_ini->points)
    if (mp) mp->updateNormalAndDepth();

  if (database_) {
    database_->add(kf_ini);
    database_->add(kf_cur);
  }
  sink_(kf_ini, true);
  sink_(kf_cur, true);
  current_.T_cw = kf_cur->T_cw;
  for (size_t j = 0; j < current_.size(); ++j)
    if (current_.points[j] && current_.points[j]->bad) current_.points[j] = nullptr;
  reference_kf_ = kf_cur;
  last_kf_ = kf_cur;
  last_kf_frame_ = current_.index;
  current_.reference = kf_cur;
  local_kfs_ = {kf_cur, kf_ini};
  local_points_.assign(map_.points().begin(), map_.points().end());
  state_ = TrackingState::Ok;
  initialised_at_ = current_.index;
  inliers_ = kf_cur->trackedPoints(1);
  records_.push_back(
      {init_frame_.index, init_frame_.timestamp, kf_ini, Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()});
  backfillInitialFrames(kf_ini, kf_cur);
  records_.push_back({current_.index, current_.timestamp, kf_cur, Eigen::Isometry3d::Identity(), current_.T_cw});
  last_ = current_;
  init_active_ = false;
  return true;
}

// Frames seen while waiting for enough parallax get a pose too: an interpolated guess, the initial
// map's points searched by projection, and pose-only optimisation.
void Tracker::backfillInitialFrames(KeyFrame* kf_ini, KeyFrame* kf_cur) {
  const Frame saved = current_;
  const Eigen::Isometry3d T_wc_cur = kf_cur->T_cw.inverse();
  const Eigen::Quaterniond q0 = Eigen::Quaterniond::Identity(), q1(T_wc_cur.linear());
  const double span = static_cast<double>(kf_cur->frame_index - kf_ini->frame_index);
  std::vector<MapPoint*> points(map_.points().begin(), map_.points().end());
  for (const Frame& f : init_between_) {
    const double a = (f.index - kf_ini->frame_index) / span;
    Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
    T_wc.linear() = q0.slerp(a, q1).toRotationMatrix();
    T_wc.translation() = a * T_wc_cur.translation();
    current_ = f;
    current_.clearMatches();
    current_.T_cw = T_wc.inverse();
    for (MapPoint* mp : points) isInFrustum(mp, 0.5f);
    matching::searchLocalPoints(current_, points, pyramid_, 4.f, 0.8f);
    optimizeFramePose();
    int inliers = 0;
    for (size_t i = 0; i < current_.size(); ++i) inliers += current_.points[i] && !current_.outlier[i];
    if (inliers >= options_.tracking.min_tracked_inliers)
      records_.push_back({f.index, f.timestamp, kf_ini, current_.T_cw * kf_ini->T_cw.inverse(), current_.T_cw});
  }
  for (MapPoint* mp : points) mp->track_in_view = false;
  init_between_.clear();
  current_ = saved;
}

int Tracker::trackedOnStaticObjects() const {
  int n = 0;
  for (size_t i = 0; i < last_.points.size(); ++i) {
    const MapPoint* mp = last_.points[i];
    if (mp && !mp->bad && !last_.outlier[i] && mp->trusted) ++n;
  }
  return n;
}

std::vector<bool> Tracker::matchedKeypoints(int64_t index) const {
  if (last_.index != index) return {};
  std::vector<bool> matched(last_.points.size(), false);
  for (size_t i = 0; i < last_.points.size(); ++i)
    matched[i] = last_.points[i] && !last_.points[i]->bad && !last_.outlier[i];
  return matched;
}

void Tracker::rescale(double s) {
  for (Frame* f : {&current_, &last_, &init_frame_}) f->T_cw.translation() *= s;
  for (Frame& f : init_between_) f.T_cw.translation() *= s;
  if (velocity_) velocity_->translation() *= s;
  if (last_good_pose_) last_good_pose_->translation() *= s;
  for (FrameRecord& r : records_) {
    r.T_c_ref.translation() *= s;
    r.T_cw_online.translation() *= s;
  }
}

void Tracker::rescaleFrom(const KeyFrame* first_kf, const Eigen::Vector3d& c, double s) {
  auto move = [&](Eigen::Isometry3d& T_cw) {
    const Eigen::Vector3d centre = c + s * (T_cw.inverse().translation() - c);
    T_cw.translation() = -(T_cw.linear() * centre);
  };
  for (Frame* f : {&current_, &last_}) move(f->T_cw);
  if (velocity_) velocity_->translation() *= s;
  if (last_good_pose_) move(*last_good_pose_);
  for (FrameRecord& r : records_) {
    if (r.index < first_kf->frame_index) continue;
    if (r.reference && r.reference->id >= first_kf->id) r.T_c_ref.translation() *= s;
    move(r.T_cw_online);
  }
}

void Tracker::forgetCulled() {
  for (FrameRecord& r : records_) {
    while (r.reference && r.reference->bad && r.reference->parent) {
      r.T_c_ref = r.T_c_ref * r.reference->T_cp;
      r.reference = r.reference->parent;
    }
  }
  auto live = [](KeyFrame* kf) {
    while (kf && kf->bad) kf = kf->parent;
    return kf;
  };
  reference_kf_ = live(reference_kf_);
  if (last_kf_ && last_kf_->bad) last_kf_ = map_.keyframes().empty() ? nullptr : *map_.keyframes().rbegin();
  local_kfs_.erase(std::remove_if(local_kfs_.begin(), local_kfs_.end(), [](KeyFrame* kf) { return kf->bad; }),
                   local_kfs_.end());
  local_points_.erase(std::remove_if(local_points_.begin(), local_points_.end(), [](MapPoint* mp) { return mp->bad; }),
                      local_points_.end());
  for (Frame* f : {&current_, &last_, &init_frame_}) {
    f->reference = live(f->reference);
    for (MapPoint*& mp : f->points)
      if (mp && mp->bad) mp = mp->latest()->bad ? nullptr : mp->latest();
  }
  for (Frame& f : init_between_)
    for (MapPoint*& mp : f.points)
      if (mp && mp->bad) mp = mp->latest()->bad ? nullptr : mp->latest();
}

void Tracker::followCorrection(const std::map<long, Eigen::Isometry3d>& T_cw_before) {
  auto follow = [&](Eigen::Isometry3d& T_cw, const KeyFrame* ref) {
    if (!ref) return;
    const auto it = T_cw_before.find(ref->id);
    if (it != T_cw_before.end()) T_cw = T_cw * it->second.inverse() * ref->T_cw;
  };
  follow(current_.T_cw, current_.reference ? current_.reference : reference_kf_);
  follow(last_.T_cw, last_.reference ? last_.reference : reference_kf_);
  if (last_good_pose_) follow(*last_good_pose_, reference_kf_);
}

void Tracker::reset() {
  if (map_.numKeyFrames() > 0) ++resets_;
  if (on_reset_) on_reset_();  // first: with concurrent mapping it waits for the mapper to let go of the map
  map_.clear();
  if (database_) database_->clear();
  state_ = TrackingState::NotInitialized;
  init_active_ = false;
  init_between_.clear();
  velocity_.reset();
  reference_kf_ = last_kf_ = nullptr;
  local_kfs_.clear();
  local_points_.clear();
  last_ = current_ = Frame();  // their map points are gone with the map
  last_good_pose_.reset();
  records_.clear();  // poses before a reset live in another world frame
}

// ---------------------------------------------------------------- frame-to-frame

int Tracker::optimizeFramePose() {
  std::vector<optimize::PoseObservation> obs;
  std::vector<size_t> idx;
  for (size_t i = 0; i < current_.size(); ++i) {
    MapPoint* mp = current_.points[i];
    if (!mp) continue;
    const cv::KeyPoint& kp = current_.features->keypoints[i];
    double inv_sigma = pyramid_.inv_scale[kp.octave];
    if (mp->trusted) inv_sigma *= std::sqrt(options_.static_object_weight);
    obs.push_back({mp->position, Eigen::Vector2d(kp.pt.x, kp.pt.y), inv_sigma});
    idx.push_back(i);
  }
  std::vector<bool> outlier;
  const int inliers = optimize::optimizePose(camera_, obs, current_.T_cw, outlier);
  for (size_t k = 0; k < idx.size(); ++k) current_.outlier[idx[k]] = outlier[k];
  current_.has_pose = true;
  return inliers;
}

int Tracker::discardOutliers() {
  int in_map = 0;
  for (size_t i = 0; i < current_.size(); ++i) {
    if (!current_.points[i]) continue;
    if (current_.outlier[i]) {
      current_.points[i]->track_in_view = false;
      current_.points[i]->last_seen_frame = current_.index;
      current_.points[i] = nullptr;
      current_.outlier[i] = false;
    } else if (current_.points[i]->numObservations() > 0) {
      ++in_map;
    }
  }
  return in_map;
}

bool Tracker::trackWithMotionModel() {
  current_.T_cw = (*velocity_) * last_.T_cw;
  current_.clearMatches();
  int n = matching::searchByProjection(current_, last_, camera_, pyramid_, 15.f);
  if (n < 20) {
    current_.clearMatches();
    n = matching::searchByProjection(current_, last_, camera_, pyramid_, 30.f);
  }
  if (n < 20) return false;
  optimizeFramePose();
  return discardOutliers() >= 10;
}

bool Tracker::trackReferenceKeyFrame() {
  KeyFrame* ref = validReference();
  if (!ref || !last_.has_pose) return false;
  // ORB-SLAM2: the reference keyframe's points matched by bag of words, starting from the last pose.
  if (options_.tracking.bow_matching && vocabulary_ && !ref->feature_vector.empty()) {
    computeBow(current_);
    current_.clearMatches();
    if (matching::searchByBoW(ref, current_, 0.7f, true) >= 15) {
      current_.T_cw = last_.T_cw;
      optimizeFramePose();
      if (discardOutliers() >= 10) return true;
    }
  }
  const Eigen::Isometry3d guess = velocity_ ? (*velocity_) * last_.T_cw : last_.T_cw;
  for (float radius : {20.f, 50.f}) {
    current_.clearMatches();
    current_.T_cw = guess;
    const int n = matching::searchByProjectionWide(current_, ref->validPoints(), guess, camera_, pyramid_, radius, 0.7f,
                                                   matching::kThHigh);
    if (n < 15) continue;
    optimizeFramePose();
    if (discardOutliers() >= 10) return true;
  }
  return false;
}

bool Tracker::relocalise() {
  if (vocabulary_ && database_ && relocaliseByBoW()) return true;
  return relocaliseNearLastPose();
}

// ORB-SLAM2's relocalisation: keyframes sharing many words (grouped with their covisible neighbours),
// BoW matching (ratio 0.75, >= 15 matches), EPnP in RANSAC, pose-only optimisation, more matches by
// projection of the candidate's points when short of 50 inliers; success with 50 inliers or more.
bool Tracker::relocaliseByBoW() {
  computeBow(current_);
  const auto candidates = database_->relocalisationCandidates(current_.bow);
  if (std::getenv("BESLAM_ORB_DEBUG"))
    std::fprintf(stderr, "frame %ld: relocalisation, %zu candidates\n", static_cast<long>(current_.index),
                 candidates.size());
  for (KeyFrame* kf : candidates) {
    if (kf->bad) continue;
    if (relocaliseWith(kf)) {
      last_reloc_frame_ = current_.index;
      return true;
    }
  }
  current_.clearMatches();
  return false;
}

bool Tracker::relocaliseWith(KeyFrame* kf) {
  current_.clearMatches();
  const int bow_matches = matching::searchByBoW(kf, current_, 0.75f, true);
  if (std::getenv("BESLAM_ORB_DEBUG"))
    std::fprintf(stderr, "  keyframe %ld (frame %ld): %d BoW matches\n", kf->id, static_cast<long>(kf->frame_index),
                 bow_matches);
  if (bow_matches < 15) return false;
  // Reprojection threshold: chi-square 5.991 (2 dof) at level 0, sqrt(5.991) = 2.45 px.
  const int pnp_inliers =
      poseFromMatches(current_, camera_, {options_.seed + static_cast<uint64_t>(kf->id), 2.45f, 10, true});
  if (pnp_inliers < 0) return false;
  int good = optimizeFramePose();
  if (std::getenv("BESLAM_ORB_DEBUG"))
    std::fprintf(stderr, "  PnP inliers %d, after pose optimisation %d\n", pnp_inliers, good);
  if (good < 10) return false;
  for (size_t i = 0; i < current_.size(); ++i)
    if (current_.outlier[i]) {
      current_.points[i] = nullptr;
      current_.outlier[i] = false;
    }
  // Short of 50: the candidate's other points by projection (window 10, then 3 with the refined pose).
  const std::vector<MapPoint*> kf_points = kf->validPoints();
  auto searchMore = [&](float radius) {
    std::vector<MapPoint*> unmatched;
    std::vector<MapPoint*> matched = current_.points;
    std::sort(matched.begin(), matched.end());
    for (MapPoint* mp : kf_points)
      if (!std::binary_search(matched.begin(), matched.end(), mp)) unmatched.push_back(mp);
    Frame probe = current_;
    probe.clearMatches();
    matching::searchByProjectionWide(probe, unmatched, current_.T_cw, camera_, pyramid_, radius, 0.9f,
                                     matching::kThHigh);
    int added = 0;
    for (size_t i = 0; i < current_.size(); ++i)
      if (probe.points[i] && !current_.points[i]) {
        current_.points[i] = probe.points[i];
        ++added;
      }
    return added;
  };
  if (good < 50) {
    if (good + searchMore(10.f) >= 50) {
      good = optimizeFramePose();
      if (good > 30 && good < 50) {
        for (size_t i = 0; i < current_.size(); ++i)
          if (current_.outlier[i]) {
            current_.points[i] = nullptr;
            current_.outlier[i] = false;
          }
        if (good + searchMore(3.f) >= 50) good = optimizeFramePose();
      }
    }
  }
  if (good < 50) return false;
  if (!carsAgreeWith(kf)) {
    ++reloc_object_rejections_;
    if (std::getenv("BESLAM_ORB_DEBUG")) std::fprintf(stderr, "  refused: its parked cars disagree\n");
    return false;
  }
  discardOutliers();
  return true;
}

// The candidate keyframe's parked cars, placed by the recovered pose, against the frame's car boxes. Only
// the cars the frame could show are expected: in front of the camera, inside the image, and no farther
// than the farthest car box of the frame (what the detector reaches here). Without boxes: no check.
bool Tracker::carsAgreeWith(const KeyFrame* kf) const {
  if (!options_.tracking.relocalisation_object_check || cars_in_view_.empty()) return true;
  double reach = 0;
  for (const Eigen::Vector3d& p : cars_in_view_) reach = std::max(reach, p.norm());
  std::vector<Eigen::Vector3d> p_cam = objects::parkedCarCentres(*kf, map_.objects());
  for (Eigen::Vector3d& p : p_cam) p = current_.T_cw * p;
  const std::vector<Eigen::Vector3d> expected = objects::carsInView(p_cam, camera_, reach);
  const objects::LayoutCheck check = objects::compareLayouts(expected, cars_in_view_, objects::LayoutOptions());
  if (std::getenv("BESLAM_ORB_DEBUG"))
    std::fprintf(stderr, "  parked-car check: %zu cars expected in view, %zu car boxes; %s (%d disagree)\n",
                 expected.size(), cars_in_view_.size(), check.decided ? "decided" : "undecided", check.disagree);
  return !check.rejected;
}

// Without a vocabulary: the last good pose's neighbourhood searched by projection, then PnP.
bool Tracker::relocaliseNearLastPose() {
  if (!last_good_pose_) return map_loaded_ && localiseInLoadedMap();
  // Candidate points: the last local map, or everything seen by the last keyframe's neighbourhood.
  std::vector<MapPoint*> points;
  KeyFrame* ref = validReference();
  if (!ref) return false;
  std::vector<KeyFrame*> kfs = ref->bestCovisibles(10);
  kfs.push_back(ref);
  int64_t stamp = current_.index;
  for (KeyFrame* kf : kfs)
    for (MapPoint* mp : kf->points)
      if (mp && !mp->bad && mp->track_ref_for_frame != -2 - stamp) {
        mp->track_ref_for_frame = -2 - stamp;
        points.push_back(mp);
      }
  current_.clearMatches();
  const int n = matching::searchByProjectionWide(current_, points, *last_good_pose_, camera_, pyramid_, 80.f, 0.75f,
                                                 matching::kThLow);
  if (n < 30) return false;
  if (poseFromMatches(current_, camera_, {options_.seed, 4.0f, 30, false}) < 0) return false;
  optimizeFramePose();
  if (discardOutliers() < 50) return false;
  last_reloc_frame_ = current_.index;
  return true;
}

// No pose to start from in a loaded map: the keyframes, nearest in frame order first, a block of them per
// frame so that a frame from elsewhere costs a bounded time; the next frame tries the next block.
bool Tracker::localiseInLoadedMap() {
  constexpr size_t kCandidatesPerFrame = 40;
  const std::vector<KeyFrame*> ordered = candidatesByFrameOrder(map_, current_.index);
  if (ordered.empty()) return false;
  std::vector<KeyFrame*> block;
  for (size_t k = 0; k < std::min(kCandidatesPerFrame, ordered.size()); ++k)
    block.push_back(ordered[(localise_offset_ + k) % ordered.size()]);
  localise_offset_ = (localise_offset_ + block.size()) % ordered.size();
  MapLocaliserOptions o;
  o.trusted_weight = options_.static_object_weight;
  o.seed = options_.seed;
  KeyFrame* kf = localiseInMap(current_, block, camera_, pyramid_, o);
  if (!kf) return false;
  localise_offset_ = 0;
  reference_kf_ = kf;
  last_reloc_frame_ = current_.index;
  ++relocalisations_;
  return true;
}

// ---------------------------------------------------------------- local map

bool Tracker::trackLocalMap() {
  updateLocalKeyFrames();
  updateLocalPoints();
  searchLocalPoints();
  optimizeFramePose();
  inliers_ = 0;
  for (size_t i = 0; i < current_.size(); ++i) {
    MapPoint* mp = current_.points[i];
    if (!mp || current_.outlier[i]) continue;
    if (!options_.localisation_only) ++mp->found;  // the map's statistics are part of the map
    if (mp->numObservations() > 0) ++inliers_;
  }
  if (std::getenv("BESLAM_ORB_DEBUG"))  // developers: how near a frame came to being lost
    std::fprintf(stderr, "frame %ld: local map %zu kfs %zu points, inliers %d\n", static_cast<long>(current_.index),
                 local_kfs_.size(), local_points_.size(), inliers_);
  if (current_.index < last_reloc_frame_ + static_cast<int64_t>(options_.tracking.fps) && inliers_ < 50) return false;
  return inliers_ >= options_.tracking.min_tracked_inliers;
}

void Tracker::updateLocalKeyFrames() {
  std::map<KeyFrame*, int, IdLess<KeyFrame>> counter;
  for (size_t i = 0; i < current_.size(); ++i) {
    MapPoint* mp = goodPoint(current_.points, i);
    if (!mp) continue;
    for (auto& [kf, idx] : mp->observations) ++counter[kf];
  }
  if (counter.empty()) return;
  local_kfs_.clear();
  int best = 0;
  KeyFrame* best_kf = nullptr;
  for (auto& [kf, n] : counter) {
    if (kf->bad) continue;
    if (n > best) {
      best = n;
      best_kf = kf;
    }
    local_kfs_.push_back(kf);
    kf->track_ref_for_frame = current_.index;
  }
  auto add = [&](KeyFrame* kf) {
    if (kf && !kf->bad && kf->track_ref_for_frame != current_.index) {
      kf->track_ref_for_frame = current_.index;
      local_kfs_.push_back(kf);
      return true;
    }
    return false;
  };
  for (size_t k = 0; k < local_kfs_.size() && local_kfs_.size() <= 80; ++k) {
    KeyFrame* kf = local_kfs_[k];
    for (KeyFrame* n : kf->bestCovisibles(10))
      if (add(n)) break;
    for (KeyFrame* c : kf->children)
      if (add(c)) break;
    add(kf->parent);
  }
  // With loop closing on, the local map is the tracker's own stretch until a loop is closed: keyframes made
  // more than loop_own_stretch_keyframes before the newest are left out, so that tracking does not join a
  // lap's two ends through points seen far ahead (it would take up the drift there, and the loop closer,
  // whose candidates must not be covisible, would find no loop; docs/place-recognition.md). Not in a
  // loaded map nor after a relocalisation: there the old keyframes are where the tracker is.
  const long stretch = options_.own_stretch_keyframes;
  if (stretch > 0 && last_kf_ && !map_loaded_ && relocalisations_ == 0 && !map_.hasLoop()) {
    auto old = [&](const KeyFrame* k) { return k->id + stretch < last_kf_->id; };
    local_kfs_.erase(std::remove_if(local_kfs_.begin(), local_kfs_.end(), old), local_kfs_.end());
    if (best_kf && old(best_kf)) {  // the reference keyframe too is one of the stretch
      best = 0;
      best_kf = nullptr;
      for (auto& [kf, n] : counter)
        if (!kf->bad && !old(kf) && n > best) best = n, best_kf = kf;
    }
  }
  if (best_kf) {
    reference_kf_ = best_kf;
    current_.reference = best_kf;
  }
}

void Tracker::updateLocalPoints() {
  local_points_.clear();
  for (KeyFrame* kf : local_kfs_)
    for (MapPoint* mp : kf->points) {
      if (!mp || mp->bad || mp->track_ref_for_frame == current_.index) continue;
      mp->track_ref_for_frame = current_.index;
      local_points_.push_back(mp);
    }
}

bool Tracker::isInFrustum(MapPoint* mp, float view_cos_limit) const {
  mp->track_in_view = false;
  const Eigen::Vector3d pc = current_.T_cw * mp->position;
  if (pc.z() <= 0) return false;
  const Eigen::Vector2d uv = project(camera_, pc);
  if (!inImage(camera_, uv.x(), uv.y())) return false;
  const Eigen::Vector3d po = mp->position - current_.T_cw.inverse().translation();
  const double dist = po.norm();
  if (dist < 0.8 * mp->min_distance || dist > 1.2 * mp->max_distance) return false;
  const double view_cos = po.dot(mp->normal) / dist;
  if (view_cos < view_cos_limit) return false;
  mp->track_in_view = true;
  mp->track_u = static_cast<float>(uv.x());
  mp->track_v = static_cast<float>(uv.y());
  mp->track_level = mp->predictLevel(dist, pyramid_);
  mp->track_view_cos = static_cast<float>(view_cos);
  return true;
}

void Tracker::searchLocalPoints() {
  for (size_t i = 0; i < current_.size(); ++i) {
    MapPoint* mp = goodPoint(current_.points, i);
    if (!mp) continue;
    if (!options_.localisation_only) ++mp->visible;
    mp->last_seen_frame = current_.index;
    mp->track_in_view = false;
  }
  int to_match = 0;
  for (MapPoint* mp : local_points_) {
    if (mp->last_seen_frame == current_.index || mp->bad) continue;
    if (isInFrustum(mp, 0.5f)) {
      if (!options_.localisation_only) ++mp->visible;
      ++to_match;
    }
  }
  if (to_match == 0) return;
  const float th = current_.index < last_reloc_frame_ + 2 ? 5.f : 1.f;
  matching::searchLocalPoints(current_, local_points_, pyramid_, th, 0.8f);
}

// ---------------------------------------------------------------- keyframes

bool Tracker::needNewKeyFrame() const {
  const int n_kfs = static_cast<int>(map_.numKeyFrames());
  const int max_frames = static_cast<int>(options_.tracking.fps);
  if (current_.index < last_reloc_frame_ + max_frames && n_kfs > max_frames) return false;
  KeyFrame* ref = reference_kf_;
  if (!ref) return true;
  const int min_obs = n_kfs <= 2 ? 2 : 3;
  const int ref_matches = ref->trackedPoints(min_obs);
  // ORB-SLAM inserts when local mapping is idle, which on KITTI is about every other frame. Inline and
  // threaded mapping finish before the next frame, so a minimum gap stands in for "busy"; with concurrent
  // mapping accepts_keyframe_ asks the mapper itself.
  const int64_t since = current_.index - last_kf_frame_;
  const bool c1 = since >= max_frames || since >= options_.tracking.keyframe_min_gap;
  // ORB-SLAM2's rule for a camera with depth: few of the keypoints with a depth tracked and many more to
  // map. In a thin stretch the reference's count is small, so the ratio alone asks too late (the frame is
  // near the inlier floor by then); this asks while the keypoints the scan measured can still become points.
  // The ratio compares like with like: points that one keyframe's scan made and no other keyframe has seen
  // yet are not in the reference's count (seen 3 times or more), so they are not counted here either;
  // counting them would hold back every keyframe until the scan's points run out.
  bool need_close = false;
  int settled_inliers = inliers_;
  if (lidar_points_) {
    int tracked = 0, untracked = 0;
    for (size_t i = 0; i < current_.size(); ++i) {
      const MapPoint* mp = current_.points[i];
      const bool matched = mp && !current_.outlier[i] && !mp->bad;
      if (matched && mp->from_range && mp->numObservations() < 2) --settled_inliers;
      if (!(current_.features->lidarRange(i) > 0)) continue;
      if (matched)
        ++tracked;
      else
        ++untracked;
    }
    need_close = tracked < 100 && untracked > 70;
  }
  // A thin map (most points seen twice) leaves the reference's count small, so the ratio asks late: a frame
  // near the tracking floor asks too, while it still tracks enough points to make new ones.
  const bool near_floor = inliers_ < options_.tracking.keyframe_floor_ratio * options_.tracking.min_tracked_inliers;
  const bool c2 = (settled_inliers < ref_matches * options_.tracking.keyframe_ref_ratio || need_close || near_floor) &&
                  inliers_ > 15;
  return c1 && c2 && (!accepts_keyframe_ || accepts_keyframe_());
}

void Tracker::createKeyFrame() {
  computeBow(current_);
  KeyFrame* kf = map_.createKeyFrame(current_, camera_, pyramid_);
  if (database_ && vocabulary_) database_->add(kf);
  reference_kf_ = kf;
  current_.reference = kf;
  last_kf_ = kf;
  last_kf_frame_ = current_.index;
  sink_(kf, false);
}

}  // namespace beslam::orb
