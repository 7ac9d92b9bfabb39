// Local mapping, run once per new keyframe: register its observations, cull recent points that are
// rarely found, triangulate new points with the best covisible keyframes (epipolar search), fuse
// duplicates with first- and second-order neighbours, local bundle adjustment, keyframe culling.
// It reads Options::mapping, and for the map's scale Options::scale (the ground prior, metric scale from
// the camera height, the parked cars' boxes and the LiDAR ranges: it asks for rescales, the facade applies
// them), Options::object_landmarks and Options::static_object_weight for local BA's terms. Keyframe poses
// are T_cw (world to camera); the world is in metres once metric() says so.
#pragma once

#include <atomic>
#include <list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "beslam_orb/options.hpp"
#include "features/scale_pyramid.hpp"
#include "map/map_fwd.hpp"
#include "optimize/bundle_adjustment.hpp"

namespace beslam::orb {

// A scale correction the mapper asks for: the map from keyframe first_kf_id on times factor.
struct ScaleCorrection {
  long first_kf_id = 0;
  double factor = 1;
};

class LocalMapper {
 public:
  // objects and static_object_weight: local BA's object-landmark factors and trusted points' weight.
  LocalMapper(Map& map, const Camera& camera, const ScalePyramid& pyramid, const MappingOptions& mapping,
              const ScaleOptions& scale, const ObjectLandmarkOptions& objects, double static_object_weight);

  // The whole pipeline for one keyframe. `run_ba` = false skips BA and culling (used for the initial map).
  void processKeyFrame(KeyFrame* kf, bool run_ba = true);
  // Concurrent mapping (mapping/map_gate.hpp): the mapper lets a waiting tracker through `gate` at its safe
  // points, and when `stop_ba` is set it ends a local BA after its robust pass (ORB-SLAM2's interruption
  // when tracking wants a keyframe). Both null (default): no safe points, every BA runs to its end.
  void setConcurrency(MapGate* gate, const std::atomic<bool>* stop_ba) {
    gate_ = gate;
    stop_ba_ = stop_ba;
  }
  // A scale event is waiting for the caller (takePendingScale / takePendingCorrection).
  bool hasPendingScaleEvent() const { return pending_scale_.has_value() || pending_correction_.has_value(); }
  void reset() {
    recent_.clear();
    ground_reference_ = makeGroundReference();
    metric_ = false;
    pending_scale_.reset();
    scale_fits_.clear();
    pending_correction_.reset();
    object_reference_ = GroundReference(ground_.reference_keyframes, scale_.metric_max_spread);
    object_scaled_ = false;
    lidar_reference_ = GroundReference(scale_.lidar_reference_keyframes, scale_.metric_max_spread);
    lidar_scaled_ = false;
  }
  // Culled map points are about to be freed (Map::releaseCulled): drop them from the recent points.
  void forgetCulled();
  // The factor the map should be multiplied by to be in metres, once, when the mapper has found it;
  // the caller rescales map and tracker (with no mapping running) and calls rescale(s) here.
  std::optional<double> takePendingScale() {
    auto s = pending_scale_;
    pending_scale_.reset();
    return s;
  }
  void rescale(double s, long current_kf_id) {
    ground_reference_.rescale(s);
    // Metric now: the reference is the rig's camera height itself, not the (rescaled) median of the early
    // fits, which the scale was taken from the map as it is now, not then.
    ground_reference_.setHeight(metric_camera_height_);
    metric_ = true;
    metric_since_kf_ = current_kf_id;
    scale_fits_.clear();
  }
  // A local scale correction, once, when the metric map's recent ground fits ask for one
  // (ScaleOptions::metric_correction_min).
  std::optional<ScaleCorrection> takePendingCorrection() {
    auto c = pending_correction_;
    pending_correction_.reset();
    return c;
  }
  // The scale came from parked cars' boxes: the ground fits no longer correct it and the ground prior is
  // off (their biases on bare or sloping roads would undo a direct measurement); the boxes' range priors
  // hold the scale.
  void objectScaled() {
    object_scaled_ = true;
    scale_fits_.clear();
    pending_correction_.reset();
  }
  bool metric() const { return metric_; }
  // Local BA's options with the metric terms it has now: the parked cars' anchors and the object landmarks
  // once the map is metric, the LiDAR ranges once the scan holds its scale (the loop's global BA takes them).
  optimize::BundleAdjustmentOptions metricTerms() const;
  // Local BA's options without the metric terms (the mapping, object-landmark and trusted-point settings).
  const optimize::BundleAdjustmentOptions& bundleAdjustmentOptions() const { return ba_; }
  // The LiDAR ranges gave the scale and hold it (ScaleOptions::lidar_scale).
  bool lidarScaled() const { return lidar_scaled_; }
  // Each live keyframe's camera height over its own ground fit, in the map's unit as it is now (keyframes
  // without a fit left out), oldest first.
  std::vector<std::pair<KeyFrame*, double>> keyFrameGroundHeights() const;
  // Reference camera height of the ground prior (0 until the first fits have set it).
  double groundReferenceHeight() const { return ground_reference_.ready() ? ground_reference_.height() : 0; }

  // Timings (ms) of the last processKeyFrame, by stage.
  const std::vector<std::pair<std::string, double>>& lastTimings() const { return timings_; }
  int lastNewPoints() const { return last_new_points_; }
  const optimize::BundleAdjustmentReport& lastBundleAdjustment() const { return last_ba_; }

  // Stages, public for tests.
  void registerKeyFrame(KeyFrame* kf);
  void cullRecentPoints(KeyFrame* kf);
  int createNewPoints(KeyFrame* kf);
  int createRangedPoints(KeyFrame* kf);
  int rangedPoints() const { return ranged_points_; }  // made by createRangedPoints, in all
  void fuseWithNeighbours(KeyFrame* kf);
  int cullKeyFrames(KeyFrame* kf);

 private:
  Map& map_;
  Camera camera_;
  const ScalePyramid& pyramid_;
  MappingOptions mapping_;
  ScaleOptions scale_;
  // What the options make of local BA and the ground fits, and the scale sources in use (0: off):
  optimize::BundleAdjustmentOptions ba_;  // without the metric terms (metricTerms)
  GroundPlaneOptions ground_;             // ground-height prior in local BA (on with ground_prior or metric_scale)
  // Metric scale (on when > 0, with the ground prior): the rig's camera height over the road in metres.
  // Once the ground reference is confident, the mapper asks for the map to be rescaled so that the
  // reference height becomes this; the ground prior then holds it (metres from then on).
  double metric_camera_height_ = 0;
  double object_range_sigma_ = 0;  // the parked cars' boxes as a scale source and hold (metric_scale, object_scale)
  double lidar_range_sigma_ = 0;   // the LiDAR ranges as a scale source and hold (metric_scale, lidar_scale)
  std::list<MapPoint*> recent_;
  std::vector<std::pair<std::string, double>> timings_;
  MapGate* gate_ = nullptr;
  const std::atomic<bool>* stop_ba_ = nullptr;
  void yieldPoint();  // a safe point (see setConcurrency)
  int last_new_points_ = 0, ranged_points_ = 0;
  double currentGroundHeight(KeyFrame* kf) const;
  std::optional<double> objectScale(const KeyFrame& kf) const;
  std::optional<double> currentObjectScale(KeyFrame* kf) const;
  std::optional<double> lidarScale(const KeyFrame& kf) const;
  void measureScaleByLidar(KeyFrame* kf);
  void keepScale(KeyFrame* kf);
  GroundReference makeGroundReference() const {
    return GroundReference(ground_.reference_keyframes, metric_camera_height_ > 0 ? scale_.metric_max_spread : 1e9);
  }
  GroundReference ground_reference_;
  optimize::BundleAdjustmentReport last_ba_;
  bool metric_ = false;
  std::optional<double> pending_scale_;
  std::vector<std::pair<long, double>> scale_fits_;  // (keyframe id, camera height over its plane) once metric
  GroundReference object_reference_;                 // per-keyframe object scale observations, same agreement rule
  std::optional<ScaleCorrection> pending_correction_;
  long metric_since_kf_ = 0;
  bool object_scaled_ = false;
  GroundReference lidar_reference_;        // per-keyframe LiDAR scale observations until the scale is set
  std::atomic<bool> lidar_scaled_{false};  // read by the tracker while a concurrent mapper may set it
};

}  // namespace beslam::orb
