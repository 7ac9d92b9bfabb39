// Tracking: monocular two-view initialisation, then per frame a constant-velocity prediction searched
// by projection (reference-keyframe search as fallback: by bag of words with a vocabulary, else by
// projection), pose-only optimisation, local-map tracking and the keyframe decision. States
// NotInitialized -> Ok <-> Lost; lost with a tiny map resets it, otherwise relocalisation (BoW candidates
// from the keyframe database + PnP RANSAC with a vocabulary; a search around the last pose without).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "beslam_orb/options.hpp"
#include "beslam_orb/types.hpp"
#include "features/feature_set.hpp"
#include "features/scale_pyramid.hpp"
#include "init/two_view.hpp"
#include "map/frame.hpp"
#include "map/map_fwd.hpp"

namespace beslam::orb {

// One tracked frame, as stored for the trajectory.
struct FrameRecord {
  int64_t index;
  double timestamp;
  KeyFrame* reference;
  Eigen::Isometry3d T_c_ref;  // camera from reference keyframe
  Eigen::Isometry3d T_cw_online;
};

// What the tracker reads of Options: tracking's own options, initialisation's (the tracker initialises the
// map), and the few values of the other modules it needs. Made from a run's Options only.
struct TrackerOptions {
  explicit TrackerOptions(const Options& o)
      : tracking(o.tracking),
        init(o.init),
        seed(o.seed),
        static_object_weight(o.static_object_weight),
        localisation_only(o.map_reuse.localisation_only),
        own_stretch_keyframes(o.loop.enabled ? o.loop.own_stretch_keyframes : 0) {}
  TrackingOptions tracking;
  InitOptions init;
  uint64_t seed;                // seeds RANSAC (initialisation, relocalisation's PnP)
  double static_object_weight;  // trusted points' weight in pose optimisation
  bool localisation_only;       // track against a loaded map without changing it
  int own_stretch_keyframes;    // with loop closing, the local map's reach until a loop is closed (0: all)
};

class Tracker {
 public:
  // on_keyframe(kf, initial): hand a new keyframe to local mapping (initial = the two initial keyframes).
  using KeyFrameSink = std::function<void(KeyFrame*, bool initial)>;
  Tracker(const Camera& camera, const TrackerOptions& options, const ScalePyramid& pyramid, Map& map, KeyFrameSink sink,
          std::function<void()> on_reset, const place::Vocabulary* vocabulary = nullptr,
          KeyFrameDatabase* database = nullptr);

  TrackResult track(std::shared_ptr<const FeatureSet> features, double timestamp, int64_t index);
  // Concurrent mapping: a keyframe that the rules ask for is made only if `accepts()` says local mapping
  // can take it now (ORB-SLAM2's monocular rule: none while mapping is busy). Unset: always.
  void setKeyFrameAcceptance(std::function<bool()> accepts) { accepts_keyframe_ = std::move(accepts); }
  // The map is metric by the scan and holds it (ScaleOptions::lidar_points; local mapping makes map points from
  // keyframes' LiDAR ranges): ask for a keyframe when few of the frame's ranged keypoints are tracked. Set
  // per frame.
  void useLidarPoints(bool on) { lidar_points_ = on; }
  // The frame's car boxes (centres in the camera frame, metres, any motion state) when the map is metric,
  // for the parked-car check of relocalisation candidates (TrackingOptions::relocalisation_object_check); empty
  // otherwise (no check). Set per frame.
  void setCarsInView(std::vector<Eigen::Vector3d> p_cam) { cars_in_view_ = std::move(p_cam); }
  int relocalisationObjectRejections() const { return reloc_object_rejections_; }
  bool initialising() const { return state_ == TrackingState::NotInitialized; }
  TrackingState state() const { return state_; }
  std::optional<Eigen::Isometry3d> predictPose() const;  // T_world_cam
  const std::vector<FrameRecord>& records() const { return records_; }
  int resets() const { return resets_; }
  int relocalisations() const { return relocalisations_; }
  bool usesBow() const { return vocabulary_ != nullptr; }
  int64_t initialisedAt() const { return initialised_at_; }
  KeyFrame* lastKeyFrame() const { return last_kf_; }
  // Matched map points of the last tracked frame that lie on static objects (inliers only).
  int trackedOnStaticObjects() const;
  // Per keypoint of frame `index`, whether it is matched to a good map point and a pose inlier; empty
  // when `index` is not the last tracked frame.
  std::vector<bool> matchedKeypoints(int64_t index) const;
  // The map's unit became s times smaller (Map::rescale): scale every stored translation with it.
  void rescale(double s);
  // The map's newer part was scaled about c (Map::rescaleFrom): frames after keyframe first_kf follow.
  void rescaleFrom(const KeyFrame* first_kf, const Eigen::Vector3d& c, double s);
  // A map was loaded into the (empty) map: tracking starts lost and localises in it, by bag of words from its
  // keyframes (with a vocabulary: they join the keyframe database, which loop closing uses too), else by
  // the keyframes nearest in frame order (map_io/localise_in_map).
  void mapLoaded();
  // Culled keyframes and map points are about to be freed (Map::releaseCulled): records referenced to a
  // culled keyframe are re-anchored to its live ancestor, replaced points followed, culled ones dropped
  // from the frames, the local map and the reference / last keyframe.
  void forgetCulled();
  // A loop closure moved the keyframes (T_cw_before: their poses before, by id): the frames being
  // tracked keep their pose relative to their reference keyframe.
  void followCorrection(const std::map<long, Eigen::Isometry3d>& T_cw_before);
  // The centre of the last tracked frame (world), the fixed point of scale corrections.
  Eigen::Vector3d lastCentre() const { return last_.T_cw.inverse().translation(); }
  // The last tracked frame's pose (world from camera), empty before the first.
  std::optional<Eigen::Isometry3d> lastWorldCam() const {
    return last_.has_pose ? std::optional<Eigen::Isometry3d>(last_.T_cw.inverse()) : std::nullopt;
  }
  // The same frame's pose as the map holds it now: re-anchored to its reference keyframe, which mapping
  // (local BA) may have moved since the frame was tracked; the tracker predicts from this. Empty when the
  // last frame was not tracked.
  std::optional<Eigen::Isometry3d> lastWorldCamInMap() const {
    const auto T_cw = lastPoseInMap();
    return T_cw ? std::optional<Eigen::Isometry3d>(T_cw->inverse()) : std::nullopt;
  }

 private:
  void initialise(TrackResult& result);
  std::optional<Eigen::Isometry3d> lastPoseInMap() const;  // camera from world, see lastWorldCamInMap
  bool createInitialMap(const std::vector<int>& matches12, const TwoViewResult& r);
  void reset();
  void backfillInitialFrames(KeyFrame* kf_ini, KeyFrame* kf_cur);
  bool trackWithMotionModel();
  bool trackReferenceKeyFrame();
  bool relocalise();
  bool relocaliseByBoW();
  bool relocaliseNearLastPose();
  bool relocaliseWith(KeyFrame* kf);
  bool carsAgreeWith(const KeyFrame* kf) const;
  void computeBow(Frame& f) const;
  bool localiseInLoadedMap();
  bool trackLocalMap();
  void updateLocalKeyFrames();
  void updateLocalPoints();
  void searchLocalPoints();
  bool isInFrustum(MapPoint* mp, float view_cos_limit) const;
  int optimizeFramePose();
  int discardOutliers();
  bool needNewKeyFrame() const;
  void createKeyFrame();
  KeyFrame* validReference();

  Camera camera_;
  TrackerOptions options_;
  const ScalePyramid& pyramid_;
  Map& map_;
  KeyFrameSink sink_;
  std::function<void()> on_reset_;
  std::function<bool()> accepts_keyframe_;
  const place::Vocabulary* vocabulary_;
  KeyFrameDatabase* database_;

  TrackingState state_ = TrackingState::NotInitialized;
  Frame current_, last_;
  std::optional<Eigen::Isometry3d> velocity_;  // T_cur_last
  // Initialisation.
  bool init_active_ = false;
  Frame init_frame_;
  std::vector<cv::Point2f> prev_matched_;
  std::vector<Frame> init_between_;  // frames between the reference and the initialising frame
  // Local map.
  KeyFrame* reference_kf_ = nullptr;
  KeyFrame* last_kf_ = nullptr;
  int64_t last_kf_frame_ = -1, last_reloc_frame_ = -1000;
  std::optional<Eigen::Isometry3d> last_good_pose_;
  std::vector<KeyFrame*> local_kfs_;
  std::vector<MapPoint*> local_points_;
  int inliers_ = 0;

  std::vector<FrameRecord> records_;
  int resets_ = 0, relocalisations_ = 0;
  std::vector<Eigen::Vector3d> cars_in_view_;
  int reloc_object_rejections_ = 0;
  int64_t initialised_at_ = -1;
  bool lidar_points_ = false;
  bool map_loaded_ = false;     // never reset a loaded map
  size_t localise_offset_ = 0;  // next block of keyframes to try (localiseInLoadedMap)
};

}  // namespace beslam::orb
