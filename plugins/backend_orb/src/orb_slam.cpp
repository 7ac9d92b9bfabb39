// OrbSlam facade: wires feature extraction, tracking, local mapping (mapping/mapping_thread.hpp: inline or on
// a worker thread), loop closing and map files (map_io/map_files.hpp), and applies what mapping found (a
// metric scale, scale and loop corrections) to the map and the tracker between frames. Options::validate is
// in options.cpp.
#include "beslam_orb/orb_slam.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>

#include "features/orb_extractor.hpp"
#include "loop/loop_closer.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "map_io/map_files.hpp"
#include "mapping/local_mapper.hpp"
#include "mapping/mapping_thread.hpp"
#include "optimize/bundle_adjustment.hpp"
#include "place/keyframe_database.hpp"
#include "place/vocabulary.hpp"
#include "scale/lidar_range.hpp"
#include "scale/object_range.hpp"
#include "scale/parked_car_scale.hpp"
#include "stage_clock.hpp"
#include "tracking/tracker.hpp"

namespace beslam::orb {
namespace {

// Local mapping's options: bag-of-words triangulation only with a vocabulary.
MappingOptions withVocabulary(MappingOptions mapping, bool has_vocabulary) {
  mapping.triangulation_bow = mapping.triangulation_bow && has_vocabulary;
  return mapping;
}

}  // namespace

struct OrbSlam::Impl {
  Camera camera;
  Options options;
  OrbExtractor extractor;
  place::Vocabulary vocabulary;  // empty without Options::vocabulary
  KeyFrameDatabase database;
  Map map;
  LocalMapper mapper;
  Tracker tracker;
  std::unique_ptr<LoopCloser> loop_closer;  // with a vocabulary and Options::loop.enabled
  bool loop_pending = false;                // closed on the mapping side, not yet followed by the tracker
  std::vector<std::pair<std::string, double>> process_timings;  // the last process() call's stage times
  int reported_object_rejections = 0;
  int reported_lidar_points = 0;
  Statistics stats;
  ParkedCarScale parked_scale;
  bool object_scale_done = false;
  std::optional<double> pending_object_scale;

  // Frames prepared ahead (OrbSlam::prepare, on the host's producer thread), by frame index; taken by
  // their track(). At most kMaxPrepared are kept (the oldest go first), so frames never tracked (an
  // interrupted run) cost nothing for long.
  static constexpr size_t kMaxPrepared = 16;
  std::mutex prepared_mutex;
  std::map<int64_t, std::shared_ptr<const PreparedImage>> prepared;

  void prepare(const cv::Mat& image, int64_t index) {
    std::shared_ptr<const PreparedImage> p = extractor.prepare(image);
    std::lock_guard<std::mutex> lock(prepared_mutex);
    prepared[index] = std::move(p);
    while (prepared.size() > kMaxPrepared) prepared.erase(prepared.begin());
  }

  // The frame's prepared image if it was prepared for an image of this size; older entries are dropped.
  std::shared_ptr<const PreparedImage> takePrepared(int64_t index, const cv::Size& size) {
    std::lock_guard<std::mutex> lock(prepared_mutex);
    std::shared_ptr<const PreparedImage> p;
    if (auto it = prepared.find(index); it != prepared.end() && it->second->grey.size() == size) p = it->second;
    prepared.erase(prepared.begin(), prepared.upper_bound(index));
    return p;
  }

  std::vector<MappingThread::Job> pending;  // keyframes made during the current track() call
  MapFiles map_files;
  // Object landmarks added and objects dropped by the caller while mapping may run (threaded modes): kept in
  // call order and applied once mapping is idle, before the next frame is tracked. Inline mapping applies
  // them at once; the order against mapping is the same (a keyframe's mapping, then the caller's objects,
  // then the next frame), so every mode gives the same map, and the caller's reconstruction overlaps mapping.
  struct ObjectOp {
    std::vector<ObjectLandmark> add;
    int32_t drop = -1;
  };
  std::vector<ObjectOp> object_ops;
  // Where mapping runs (Options::threading). Last: its worker stops before the rest goes.
  MappingThread mapping;

  Impl(const Camera& c, const Options& o)
      : camera(c),
        options(o),
        extractor(o.extractor),
        vocabulary(o.vocabulary.empty() ? place::Vocabulary() : place::Vocabulary::load(o.vocabulary)),
        mapper(map, c, extractor.pyramid(), withVocabulary(o.mapping, !vocabulary.empty()), o.scale, o.object_landmarks,
               o.static_object_weight),
        tracker(
            c, TrackerOptions(o), extractor.pyramid(), map,
            [this](KeyFrame* kf, bool initial) { pending.emplace_back(kf, initial); },
            [this] {
              // the mapper finishes before the map goes
              if (options.threading.concurrent_mapping) mapping.waitIdleHoldingGate();
              mapper.reset();
              if (loop_closer) loop_closer->reset();
            },
            vocabulary.empty() ? nullptr : &vocabulary, &database),
        map_files(c, o.extractor),
        mapping(o.threading, [this](KeyFrame* kf, bool initial) { process(kf, initial); }) {
    if (options.map_reuse.localisation_only) object_scale_done = true;  // the map's unit is the loaded map's
    if (options.loop.enabled && !vocabulary.empty()) {
      LoopOptions lo;
      lo.object_check = options.loop.object_check;
      lo.global_ba_iterations = options.loop.global_ba_iterations;
      lo.global_ba_solver = optimize::baSolver(options.loop.global_ba_solver);
      lo.metric_terms = [this] { return mapper.metricTerms(); };
      lo.global_ba_objects = options.loop.global_ba_objects;
      lo.seed = options.seed;
      loop_closer = std::make_unique<LoopCloser>(map, database, extractor.pyramid(), lo);
    }
    if (options.threading.concurrent_mapping) {
      options.threading.threaded_mapping = true;
      mapper.setConcurrency(&mapping.gate(), &mapping.stopBa());
      tracker.setKeyFrameAcceptance([this] { return mapping.acceptKeyFrame(); });
    }
  }

  void loadMap(const std::string& path) {
    mapping.waitIdle();
    if (stats.frames > 0 || map.numKeyFrames() > 0)
      throw std::logic_error("OrbSlam::loadMap: only before the first frame (map file '" + path + "')");
    const MapFileInfo info = map_files.load(path, extractor.pyramid(), map);
    if (info.metric) {  // in metres already: the mapper keeps it so, the parked cars do not rescale it
      mapper.rescale(1.0, std::max(0L, map.lastKeyFrameId()));
      object_scale_done = true;
    }
    tracker.mapLoaded();
  }

  // Local mapping, then loop closing, of one keyframe; their stage times go to process_timings.
  void process(KeyFrame* kf, bool initial) {
    process_timings.clear();
    if (kf->bad) return;
    mapper.processKeyFrame(kf, !initial);
    process_timings = mapper.lastTimings();
    if (!loop_closer || initial || kf->bad) return;
    if (loop_closer->process(kf, mapper.metric())) loop_pending = true;
    const auto& loop_timings = loop_closer->lastTimings();
    process_timings.insert(process_timings.end(), loop_timings.begin(), loop_timings.end());
  }

  void applyObjectOps() {
    for (const ObjectOp& op : object_ops) {
      if (op.drop >= 0) {
        stats.object_points_dropped += map.dropObjectPoints(op.drop);
        map.objects().erase(op.drop, map.lastKeyFrameId());  // and with it its factors
      }
      for (const ObjectLandmark& l : op.add) map.objects().add(l, map.lastKeyFrameId());
    }
    object_ops.clear();
  }

  void queueObjectOp(ObjectOp op) {
    object_ops.push_back(std::move(op));
    if (!mapping.threaded()) applyObjectOps();
  }

  // Mapping idle and the caller's object changes applied: what every accessor of the map needs.
  void syncIdle() {
    mapping.waitIdle();
    applyObjectOps();
  }

  // Concurrent mapping: the tracker's turn at the map, left on every way out of track().
  struct TrackerTurn {
    MapGate* gate;
    explicit TrackerTurn(MapGate* g) : gate(g) {
      if (gate) gate->enterTracker();
    }
    ~TrackerTurn() {
      if (gate) gate->leaveTracker();
    }
    TrackerTurn(const TrackerTurn&) = delete;
    TrackerTurn& operator=(const TrackerTurn&) = delete;
  };

  // The frame's features within this frame's budget, with the ranges the boxes and the scan give them and
  // the parked cars' boxes a keyframe keeps.
  std::shared_ptr<FeatureSet> extractFeatures(const cv::Mat& image, const cv::Mat& labels, int64_t index,
                                              const std::vector<ObjectBox>& boxes, const Eigen::Matrix3Xf* lidar_cam) {
    const int budget =
        tracker.initialising() ? options.extractor.features * options.init.features_factor : options.extractor.features;
    const std::shared_ptr<const PreparedImage> prepared_image = takePrepared(index, image.size());
    auto features = extractor.extract(image, labels, budget, prepared_image.get());
    const ScaleOptions& scale = options.scale;
    if (scale.object_scale && scale.metric_scale && !boxes.empty()) setObjectRanges(*features, boxes);
    if (scale.lidar_scale && scale.metric_scale && lidar_cam) setLidarRanges(*features, *lidar_cam, camera);
    // Kept with a keyframe for the parked cars' anchors and the object landmarks' camera-object factors.
    if (options.object_landmarks.mode != ObjectLandmarkMode::Off ||
        (scale.metric_scale && scale.object_scale && scale.object_scale_hold == ObjectScaleHold::Anchors))
      for (const ObjectBox& b : boxes)
        if (b.parked && b.object_id >= 0) features->object_boxes.push_back(b);
    return features;
  }

  // How the metric world moved since the last frame: one change about the last tracked camera.
  struct WorldChange {
    std::optional<Eigen::Isometry3d> S_new_old;  // p_new = S p_old (scale world_scale); set when it moved
    double scale = 1;
    double loop_correction_m = -1;  // a loop closed: how far it moved the last camera
  };

  // With mapping idle: what mapping found since the last frame is applied to the map and the tracker
  // before this frame is tracked (the same frame in the threaded and the inline mode): a metric scale
  // (from the road, the parked cars' boxes or the scan), a scale correction, a loop correction, and the
  // keyframe local BA moved under the last frame.
  WorldChange applyMapEvents(int64_t index) {
    WorldChange change;
    const bool was_metric = mapper.metric();
    const std::optional<Eigen::Isometry3d> T_world_last_before = tracker.lastWorldCam();
    bool world_moved = false;
    if (const auto s = mapper.takePendingScale()) becomeMetric(*s, index);
    if (mapper.lidarScaled() && !stats.lidar_scaled) {
      // The scan measures the unit directly and holds it in local BA: the parked cars' fit is not needed.
      stats.lidar_scaled = true;
      object_scale_done = true;
      pending_object_scale.reset();
      if (std::getenv("BESLAM_ORB_DEBUG"))
        std::fprintf(stderr, "frame %ld: the LiDAR ranges give the scale and hold it\n", static_cast<long>(index));
    }
    if (pending_object_scale) {  // the parked cars' boxes: a direct metric measurement, preferred to the road
      const double s = *pending_object_scale;
      pending_object_scale.reset();
      if (!mapper.metric()) {
        becomeMetric(s, index);
      } else {  // already metric (by the road): a correction about the current camera
        const Eigen::Vector3d centre = tracker.lastCentre();
        map.rescaleFrom(0, s, centre);
        tracker.rescaleFrom(map.keyFrameFrom(0), centre, s);
        change.scale *= s;
        world_moved = true;
      }
      mapper.objectScaled();
      if (std::getenv("BESLAM_ORB_DEBUG"))
        std::fprintf(stderr, "frame %ld: parked cars' boxes scale the map x%.4f (%d cars agree)\n",
                     static_cast<long>(index), s, stats.object_scale_tracks);
      stats.object_scale_frame = index;
      stats.object_scale_factor = s;
    }
    const auto correction = mapper.takePendingCorrection();
    if (KeyFrame* first = correction ? map.keyFrameFrom(correction->first_kf_id) : nullptr) {
      const auto c = correction;
      const Eigen::Vector3d centre = tracker.lastCentre();
      map.rescaleFrom(c->first_kf_id, c->factor, centre);
      tracker.rescaleFrom(first, centre, c->factor);
      parked_scale.clear();  // its stored poses are in the old unit
      ++stats.scale_corrections;
      change.scale *= c->factor;
      world_moved = true;
      if (std::getenv("BESLAM_ORB_DEBUG"))
        std::fprintf(stderr, "frame %ld: scale x%.4f from keyframe %ld (frame %ld) on\n", static_cast<long>(index),
                     c->factor, c->first_kf_id, static_cast<long>(first->frame_index));
    }
    releaseCulled();
    if (loop_pending) {  // mapping closed a loop after the last frame: the tracked frames follow the map
      loop_pending = false;
      tracker.followCorrection(loop_closer->posesBefore());  // rigid: a metric map's loop keeps its scale
      parked_scale.clear();                                  // its stored poses are from before the correction
      world_moved = true;
      const LoopClosureEvent& e = loop_closer->stats().closures.back();
      change.loop_correction_m = e.correction_m;
      stats.loop_frames.emplace_back(e.frame_index, e.loop_frame_index);
      if (std::getenv("BESLAM_ORB_DEBUG"))
        std::fprintf(
            stderr,
            "frame %ld: loop closed, keyframe of frame %ld with frame %ld (%d matches), moved %.3f / %.2f deg; "
            "corrected %d keyframes in %.0f ms\n",
            static_cast<long>(index), static_cast<long>(e.frame_index), static_cast<long>(e.loop_frame_index),
            e.matches, e.correction_m, e.correction_deg, e.keyframes, e.correct_ms);
    }
    // Local BA may also have moved the keyframe the last frame was tracked against: the tracker carries
    // that frame along (its pose relative to the keyframe is kept), and so is the host told.
    std::optional<Eigen::Isometry3d> T_world_last_after = tracker.lastWorldCam();
    if (options.report_map_moves && T_world_last_after)
      if (const auto T_in_map = tracker.lastWorldCamInMap(); T_in_map && !T_in_map->isApprox(*T_world_last_after)) {
        T_world_last_after = T_in_map;
        world_moved = true;
      }
    if (world_moved && was_metric && mapper.metric() && T_world_last_before && T_world_last_after) {
      // p_new = s R p_old + t, with the last camera carried along: R = R_after R_before^T and its centre
      // c_after = s R c_before + t.
      Eigen::Isometry3d S = Eigen::Isometry3d::Identity();
      S.linear() = T_world_last_after->linear() * T_world_last_before->linear().transpose();
      S.translation() =
          T_world_last_after->translation() - change.scale * (S.linear() * T_world_last_before->translation());
      change.S_new_old = S;
    }
    return change;
  }

  // The frame's features as the host reports them, counted before tracking.
  struct FeatureCounts {
    int all = 0, on_static_objects = 0, with_lidar_range = 0;
  };
  static FeatureCounts countFeatures(const FeatureSet& features) {
    FeatureCounts c;
    c.all = static_cast<int>(features.size());
    for (size_t i = 0; i < features.size(); ++i) {
      c.on_static_objects += features.onStaticObject(i) ? 1 : 0;
      c.with_lidar_range += features.lidarRange(i) > 0 ? 1 : 0;
    }
    return c;
  }

  // Each keypoint with its label and whether tracking matched it.
  void listKeypoints(const FeatureSet& features, int64_t index, TrackResult& result) const {
    const std::vector<bool> matched = tracker.matchedKeypoints(index);
    result.keypoints.reserve(features.size());
    for (size_t i = 0; i < features.size(); ++i) {
      const cv::KeyPoint& k = features.keypoints[i];
      result.keypoints.push_back(
          {k.pt.x, k.pt.y, features.labels[i], i < matched.size() && matched[i], static_cast<uint8_t>(k.octave)});
    }
  }

  // The parked cars' scale fit takes this tracked frame's box centres. The two-view map's unit settles over
  // its first keyframes (KITTI 00: 0.76 of the later one at frames 0-5): poses from then would bias the
  // fits, so they start once local BA has run a few times.
  void feedParkedScale(const TrackResult& result, const std::vector<ObjectBox>& boxes, int64_t index) {
    if (!options.scale.metric_scale || !options.scale.object_scale || object_scale_done ||
        result.state != TrackingState::Ok ||
        static_cast<int>(map.numKeyFrames()) <= options.scale.ground_reference_keyframes)
      return;
    std::vector<std::pair<int32_t, Eigen::Vector3d>> centres;
    for (const ObjectBox& b : boxes)
      if (b.object_id >= 0) centres.emplace_back(b.object_id, b.T_cam_box.translation());
    parked_scale.addFrame(result.T_world_cam, centres);
    if (std::getenv("BESLAM_ORB_DEBUG") && index % 10 == 0) parked_scale.debugPrint(index);
    if (const auto e = parked_scale.estimate()) {
      pending_object_scale = e->scale;
      stats.object_scale_tracks = e->tracks;
      object_scale_done = true;
    }
  }

  // The keyframes this frame made go to mapping: queued for the mapping thread, or mapped here (inline
  // mode, with the mapping stages' times added to the frame's).
  void handOverKeyframes(TrackResult& result) {
    if (result.is_keyframe)  // mapping is idle: the map is as tracking left it
      for (const auto& [kf, initial] : pending)
        if (kf->id == result.keyframe_id) result.keyframe_points = observedPoints(*kf);
    auto jobs = std::move(pending);
    pending.clear();
    if (mapping.threaded()) {
      mapping.queue(jobs);
      return;
    }
    std::vector<std::pair<std::string, double>> mapping_stages;
    const auto t0 = Clock::now();
    for (auto& [kf, initial] : jobs) {
      process(kf, initial);
      mapping_stages.insert(mapping_stages.end(), process_timings.begin(), process_timings.end());
    }
    if (!jobs.empty()) {
      result.stage_ms.insert(result.stage_ms.end(), mapping_stages.begin(), mapping_stages.end());
      result.stage_ms.emplace_back("mapping", msSince(t0));
    }
  }

  TrackResult track(const cv::Mat& image, const cv::Mat& labels, double timestamp, int64_t index,
                    const std::vector<ObjectBox>& boxes, const Eigen::Matrix3Xf* lidar_cam) {
    const auto t_start = Clock::now();
    auto t0 = Clock::now();
    const std::shared_ptr<FeatureSet> features = extractFeatures(image, labels, index, boxes, lidar_cam);
    const double extract_ms = msSince(t0);
    t0 = Clock::now();
    // Inline and threaded: the mapping of the last keyframe is finished before this frame is tracked.
    // Concurrent: the tracker takes its turn at the map; a rescale, scale correction or loop correction
    // waits for an idle mapper (they move the whole map).
    TrackerTurn turn(mapping.concurrent() ? &mapping.gate() : nullptr);
    if (!mapping.concurrent()) {
      mapping.waitIdle();
    } else if ((mapper.hasPendingScaleEvent() || pending_object_scale || loop_pending || !object_ops.empty()) &&
               !mapping.idle()) {
      mapping.waitIdleHoldingGate();
    }
    applyObjectOps();
    const double wait_ms = msSince(t0);
    const int object_factors =
        mapper.lastBundleAdjustment().object_box_factors + mapper.lastBundleAdjustment().object_surface_factors;
    const WorldChange change = applyMapEvents(index);
    const double background_mapping_ms = mapping.threaded() ? mapping.takeBackgroundMs() : 0;

    const FeatureCounts counts = countFeatures(*features);
    tracker.useLidarPoints(options.scale.lidar_points && mapper.lidarScaled());
    std::vector<Eigen::Vector3d> cars_cam;
    if (mapper.metric())
      for (const ObjectBox& b : boxes) cars_cam.push_back(b.T_cam_box.translation());
    tracker.setCarsInView(std::move(cars_cam));
    const int reloc_rejections_before = tracker.relocalisationObjectRejections();
    TrackResult result = tracker.track(features, timestamp, index);
    result.relocalisation_object_rejections = tracker.relocalisationObjectRejections() - reloc_rejections_before;
    result.world_is_metric = mapper.metric();
    result.S_new_old = change.S_new_old;
    result.world_change_scale = change.scale;
    result.loop_closed = change.loop_correction_m >= 0;
    result.loop_correction_m = std::max(0.0, change.loop_correction_m);
    if (loop_closer) {
      result.loop_object_rejections = loop_closer->stats().object_rejections - reported_object_rejections;
      reported_object_rejections = loop_closer->stats().object_rejections;
    }
    result.lidar_points = mapper.rangedPoints() - reported_lidar_points;  // since the last frame
    reported_lidar_points = mapper.rangedPoints();
    result.tracked_static = tracker.trackedOnStaticObjects();
    result.object_landmarks = static_cast<int>(map.objects().size());
    result.object_factors = object_factors;
    result.features = counts.all;
    result.features_static = counts.on_static_objects;
    result.features_lidar = counts.with_lidar_range;
    listKeypoints(*features, index, result);
    feedParkedScale(result, boxes, index);
    ++stats.frames;
    if (result.state == TrackingState::Ok) ++stats.frames_tracked;
    result.stage_ms.insert(result.stage_ms.begin(), {"extract", extract_ms});
    if (mapping.threaded()) {
      result.stage_ms.emplace_back("wait_mapping", wait_ms);
      result.stage_ms.emplace_back("mapping_background", background_mapping_ms);
    }
    result.stage_ms.emplace_back("tracking_total", msSince(t_start));
    handOverKeyframes(result);
    result.stage_ms.emplace_back("total", msSince(t_start));
    return result;
  }

  // What a new keyframe hands the reconstructor: the map points it matched (with the label under their
  // keypoint), then the points made on static objects that lie in its view but it did not match (most
  // of a parked car's points are triangulated by later keyframes), with their object's label at their
  // projection. Static-object points are labelled by their object id, not by the pixel they project to,
  // so background points behind a car never pass for the car's.
  std::vector<TrackResult::ObservedPoint> observedPoints(const KeyFrame& kf) const {
    std::vector<TrackResult::ObservedPoint> out;
    std::set<long> seen;
    for (size_t i = 0; i < kf.size(); ++i)
      if (const MapPoint* mp = kf.points[i]; mp && !mp->bad) {
        out.push_back({mp->id, mp->position, kf.keypoint(i).pt.x, kf.keypoint(i).pt.y, kf.features->labels[i],
                       mp->numObservations()});
        seen.insert(mp->id);
      }
    for (const MapPoint* mp : map.points()) {
      if (mp->bad || mp->object_id < 0 || seen.count(mp->id)) continue;
      const Eigen::Vector3d p_cam = kf.T_cw * mp->position;
      if (p_cam.z() <= 0.1) continue;
      const double u = camera.fx * p_cam.x() / p_cam.z() + camera.cx, v = camera.fy * p_cam.y() / p_cam.z() + camera.cy;
      if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) continue;
      out.push_back({mp->id, mp->position, static_cast<float>(u), static_cast<float>(v),
                     static_cast<uint16_t>(1000 + mp->object_id), mp->numObservations()});
    }
    return out;
  }

  // Frees the keyframes and map points culled since the last call, once the tracker and the mapper have let
  // go of them. Only with mapping idle (inline and threaded: after waitIdle(); concurrent: skipped until then).
  void releaseCulled() {
    if (!map.hasCulled() || !mapping.idle()) return;  // concurrent mapping: later, when the mapper is idle
    tracker.forgetCulled();
    mapper.forgetCulled();
    for (KeyFrame* kf : map.culledNotReleased()) database.erase(kf);
    map.releaseCulled();
  }

  // The map, the tracker and the mapper's references times s: the world is in metres from this frame on.
  void becomeMetric(double s, int64_t index) {
    map.rescale(s);
    tracker.rescale(s);
    mapper.rescale(s, std::max(0L, map.lastKeyFrameId()));
    parked_scale.rescale(s);
    stats.metric_from_frame = index;
    stats.metric_scale_factor = s;
    if (std::getenv("BESLAM_ORB_DEBUG")) {  // the young map, now in metres: its path and its own ground fits
      double path_m = 0;
      std::optional<Eigen::Vector3d> previous;
      for (const FrameRecord& r : tracker.records()) {
        const Eigen::Vector3d c = composedPose(r).translation();
        if (previous) path_m += (c - *previous).norm();
        previous = c;
      }
      std::fprintf(stderr, "frame %ld: metric (x%.4f), camera path %.3f m over %zu frames; keyframes' ground heights:",
                   static_cast<long>(index), s, path_m, tracker.records().size());
      for (const auto& [kf, h] : mapper.keyFrameGroundHeights()) std::fprintf(stderr, " %.3f", h);
      std::fprintf(stderr, " m\n");
    }
  }

  // FeatureSet::object_range: where each static-object keypoint's ray enters its object's box (slab test).
  void setObjectRanges(FeatureSet& f, const std::vector<ObjectBox>& boxes) const {
    f.object_range.assign(f.size(), 0.0f);
    for (size_t i = 0; i < f.size(); ++i) {
      const int32_t id = f.objectId(i);
      if (id < 0) continue;
      for (const ObjectBox& b : boxes) {
        if (b.object_id != id || !b.parked) continue;
        const cv::Point2f& pt = f.keypoints[i].pt;
        const Eigen::Vector3d ray_cam =
            Eigen::Vector3d((pt.x - camera.cx) / camera.fx, (pt.y - camera.cy) / camera.fy, 1.0).normalized();
        if (const auto t = rayBoxEntry(ray_cam, b); t && *t > 0.5) f.object_range[i] = static_cast<float>(*t);
        break;
      }
    }
  }

  Eigen::Isometry3d composedPose(const FrameRecord& r) const {
    Eigen::Isometry3d T_c_ref = r.T_c_ref;
    KeyFrame* ref = r.reference;
    while (ref && ref->bad && ref->parent) {
      T_c_ref = T_c_ref * ref->T_cp;
      ref = ref->parent;
    }
    return (T_c_ref * ref->T_cw).inverse();
  }
};

OrbSlam::OrbSlam(const Camera& camera, const Options& options) {
  std::string error;
  if (!options.validate(&error)) throw std::invalid_argument("beslam::orb::Options: " + error);
  if (camera.width <= 0 || camera.height <= 0 || camera.fx <= 0 || camera.fy <= 0)
    throw std::invalid_argument("beslam::orb::Camera: width, height, fx and fy must be > 0");
  impl_ = std::make_unique<Impl>(camera, options);
  if (!options.map_reuse.load_map.empty()) impl_->loadMap(options.map_reuse.load_map);
}

OrbSlam::~OrbSlam() = default;

std::optional<Eigen::Isometry3d> OrbSlam::predictPose(double) const { return impl_->tracker.predictPose(); }

void OrbSlam::prepare(const cv::Mat& gray, int64_t frame_index) { impl_->prepare(gray, frame_index); }

TrackResult OrbSlam::track(const cv::Mat& gray, const cv::Mat& label_mask, double timestamp, int64_t frame_index,
                           const std::vector<ObjectBox>& car_boxes, const Eigen::Matrix3Xf* lidar_cam) {
  return impl_->track(gray, label_mask, timestamp, frame_index, car_boxes, lidar_cam);
}

void OrbSlam::finish() {
  impl_->syncIdle();
  KeyFrame* last = impl_->tracker.lastKeyFrame();
  if (!impl_->options.map_reuse.localisation_only && last && !last->bad && impl_->map.numKeyFrames() > 2) {
    optimize::BundleAdjustmentOptions ba = impl_->mapper.bundleAdjustmentOptions();
    ba.objects.enabled = ba.objects.enabled && impl_->mapper.metric();  // as in local mapping
    optimize::localBundleAdjustment(last, impl_->map, ba);
  }
  impl_->releaseCulled();
  if (!impl_->options.map_reuse.save_map.empty()) saveMap(impl_->options.map_reuse.save_map);
}

void OrbSlam::saveMap(const std::string& path) const {
  impl_->syncIdle();
  impl_->map_files.save(path, impl_->map, impl_->mapper.metric());
}

void OrbSlam::loadMap(const std::string& path) { impl_->loadMap(path); }

std::vector<FramePose> OrbSlam::trajectory() const {
  impl_->syncIdle();
  std::vector<FramePose> out;
  for (const FrameRecord& r : impl_->tracker.records()) out.push_back({r.index, r.timestamp, impl_->composedPose(r)});
  return out;
}

std::vector<FramePose> OrbSlam::onlineTrajectory() const {
  impl_->syncIdle();
  std::vector<FramePose> out;
  for (const FrameRecord& r : impl_->tracker.records()) out.push_back({r.index, r.timestamp, r.T_cw_online.inverse()});
  return out;
}

std::vector<FramePose> OrbSlam::keyframes() const {
  impl_->syncIdle();
  std::vector<FramePose> out;
  for (KeyFrame* kf : impl_->map.keyframes()) out.push_back({kf->frame_index, kf->timestamp, kf->T_cw.inverse()});
  return out;
}

std::vector<CloudPoint> OrbSlam::mapPoints() const {
  impl_->syncIdle();
  std::vector<CloudPoint> out;
  for (MapPoint* mp : impl_->map.points()) {
    if (mp->bad) continue;
    CloudPoint p;
    p.position = mp->position;
    p.grey = mp->grey;
    p.r = mp->r;
    p.g = mp->g;
    p.b = mp->b;
    p.observations = mp->numObservations();
    p.on_static_object = mp->trusted;
    out.push_back(p);
  }
  return out;
}

void OrbSlam::addObjectLandmarks(const std::vector<ObjectLandmark>& landmarks) {
  if (impl_->options.map_reuse.localisation_only) return;  // the loaded map's landmarks stay as they are
  impl_->queueObjectOp({landmarks, -1});                   // local BA reads and moves them: once mapping is idle
}

std::vector<ObjectLandmark> OrbSlam::objectLandmarks() const {
  impl_->syncIdle();
  return impl_->map.objects().landmarks();
}

void OrbSlam::dropObject(int32_t object_id) {
  if (impl_->options.map_reuse.localisation_only) return;  // the map does not change
  impl_->queueObjectOp({{}, object_id});                   // once mapping is idle
}

Statistics OrbSlam::statistics() const {
  impl_->syncIdle();
  Statistics s = impl_->stats;
  s.keyframes = static_cast<int>(impl_->map.numKeyFrames());
  s.keyframes_culled = impl_->map.culledKeyFrames();
  s.map_points = static_cast<int>(impl_->map.points().size());
  s.resets = impl_->tracker.resets();
  s.relocalisations = impl_->tracker.relocalisations();
  s.relocalisation_object_rejections = impl_->tracker.relocalisationObjectRejections();
  s.lidar_points = impl_->mapper.rangedPoints();
  if (impl_->loop_closer) {
    const LoopStats& l = impl_->loop_closer->stats();
    s.loop_closures = static_cast<int>(l.closures.size());
    s.loop_object_rejections = l.object_rejections;
    s.loop_candidates = l.candidates_checked;
  }
  s.initialised_at_frame = impl_->tracker.initialisedAt();
  return s;
}

const Options& OrbSlam::options() const { return impl_->options; }

}  // namespace beslam::orb
