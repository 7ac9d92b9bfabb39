#include "loop/loop_closer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>

#include "loop/pose_graph.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "matching/matcher.hpp"
#include "objects/object_layout.hpp"
#include "objects/object_store.hpp"
#include "optimize/bundle_adjustment.hpp"
#include "optimize/pnp_pose.hpp"
#include "optimize/pose_optimizer.hpp"
#include "place/keyframe_database.hpp"
#include "stage_clock.hpp"

namespace beslam::orb {
namespace {

using loop::Sim3;

constexpr int kCovisibilityEdgeWeight = 100;  // ORB-SLAM2's essential graph threshold

loop::PinholeIntrinsics intrinsics(const Camera& c) { return {c.fx, c.fy, c.cx, c.cy}; }

// The parked cars a keyframe sees (objects/object_layout.hpp), in the frame that `to_camera` maps the world into.
std::vector<Eigen::Vector3d> parkedCars(const KeyFrame* kf, const objects::ObjectStore& store, const Sim3& to_camera) {
  std::vector<Eigen::Vector3d> out = objects::parkedCarCentres(*kf, store);
  for (Eigen::Vector3d& p : out) p = to_camera * p;
  return out;
}

}  // namespace

LoopCloser::LoopCloser(Map& map, KeyFrameDatabase& database, const ScalePyramid& pyramid, const LoopOptions& options)
    : map_(map), database_(database), pyramid_(pyramid), options_(options) {}

void LoopCloser::reset() {
  groups_.clear();
  last_loop_kf_id_ = -1;
  poses_before_.clear();
}

std::vector<KeyFrame*> LoopCloser::detect(KeyFrame* kf) {
  if (kf->bow.empty() || map_.numKeyFrames() < 10) return {};
  if (last_loop_kf_id_ >= 0 && kf->id < last_loop_kf_id_ + options_.min_keyframes_since_loop) return {};

  // The worst BoW score among the keyframe's covisible neighbours: a loop must look at least as similar.
  std::set<long> connected{kf->id};
  double min_score = 1.0;
  for (KeyFrame* c : kf->covisibles()) {
    connected.insert(c->id);
    if (!c->bad && !c->bow.empty()) min_score = std::min(min_score, place::Vocabulary::score(kf->bow, c->bow));
  }
  int max_common = 0;
  const auto shared = database_.sharedWords(kf->bow);
  for (const auto& [ki, n] : shared)
    if (!connected.count(ki->id)) max_common = std::max(max_common, n);
  const int min_common = static_cast<int>(0.8 * max_common);
  std::map<long, std::pair<KeyFrame*, double>> scored;  // by id: deterministic order
  for (const auto& [ki, n] : shared) {
    if (ki->bad || connected.count(ki->id) || n < min_common || n == 0) continue;
    const double s = place::Vocabulary::score(kf->bow, ki->bow);
    if (s >= min_score) scored[ki->id] = {ki, s};
  }

  // Groups: a candidate and its best covisible neighbours that are candidates too.
  std::vector<std::pair<KeyFrame*, double>> groups;
  double best_group = 0;
  for (const auto& [id, entry] : scored) {
    auto [best, best_score] = entry;
    double accumulated = entry.second;
    for (KeyFrame* n : entry.first->bestCovisibles(10)) {
      const auto it = scored.find(n->id);
      if (it == scored.end()) continue;
      accumulated += it->second.second;
      if (it->second.second > best_score) best = n, best_score = it->second.second;
    }
    groups.emplace_back(best, accumulated);
    best_group = std::max(best_group, accumulated);
  }
  std::vector<KeyFrame*> candidates;
  for (const auto& [best, accumulated] : groups)
    if (accumulated >= 0.75 * best_group && std::find(candidates.begin(), candidates.end(), best) == candidates.end())
      candidates.push_back(best);

  // Consistency over consecutive keyframes.
  std::vector<Group> current;
  std::vector<bool> continued(groups_.size(), false);
  std::vector<KeyFrame*> consistent;
  for (KeyFrame* cand : candidates) {
    Group g;
    g.keyframe_ids.insert(cand->id);
    for (KeyFrame* c : cand->covisibles()) g.keyframe_ids.insert(c->id);
    bool any = false, enough = false;
    for (size_t i = 0; i < groups_.size(); ++i) {
      const bool overlap = std::any_of(g.keyframe_ids.begin(), g.keyframe_ids.end(),
                                       [&](long id) { return groups_[i].keyframe_ids.count(id) > 0; });
      if (!overlap) continue;
      any = true;
      const int c = groups_[i].consistency + 1;
      if (!continued[i]) {
        current.push_back({g.keyframe_ids, c});
        continued[i] = true;
      }
      if (c >= options_.consistency && !enough) {
        consistent.push_back(cand);
        enough = true;
      }
    }
    if (!any) current.push_back({g.keyframe_ids, 0});
  }
  groups_ = std::move(current);
  if (std::getenv("BESLAM_ORB_DEBUG")) {
    // The oldest covisible keyframe shows where tracking has already joined the map's far end: such a
    // keyframe is excluded as a candidate like any covisible one (ORB-SLAM2's rule).
    const KeyFrame* oldest = nullptr;
    for (const KeyFrame* c : kf->covisibles())
      if (!oldest || c->frame_index < oldest->frame_index) oldest = c;
    std::fprintf(
        stderr,
        "  loop detection, keyframe of frame %ld: %zu covisible (oldest frame %ld), %zu scored, %zu consistent\n",
        static_cast<long>(kf->frame_index), kf->covisibles().size(),
        oldest ? static_cast<long>(oldest->frame_index) : -1L, scored.size(), consistent.size());
  }
  return consistent;
}

// The loop transform from 3D-3D matches: the loop keyframe's map points against the new keyframe's map
// points, found by bag of words, in a seeded Sim3 RANSAC (SE3 once metric). Only the new keyframe's
// keypoints with a map point are searched (ORB-SLAM2 matches map point to map point here): a keypoint
// without one would take a loop point, or spoil its ratio test, without giving a measurement.
std::optional<LoopCloser::Hypothesis> LoopCloser::fromPointMatches(KeyFrame* kf, KeyFrame* loop_kf, bool metric,
                                                                   bool debug) {
  Frame probe(kf->frame_index, kf->timestamp, kf->features);
  for (const auto& [node, indices] : kf->feature_vector) {
    std::vector<int> with_point;
    for (int j : indices)
      if (kf->points[static_cast<size_t>(j)] && !kf->points[static_cast<size_t>(j)]->bad) with_point.push_back(j);
    if (!with_point.empty()) probe.feature_vector.emplace(node, std::move(with_point));
  }
  probe.has_bow = true;
  const int bow_matches = matching::searchByBoW(loop_kf, probe, 0.75f, true);
  if (debug)
    std::fprintf(stderr, "  loop candidate frame %ld for frame %ld: %d BoW matches point to point\n",
                 static_cast<long>(loop_kf->frame_index), static_cast<long>(kf->frame_index), bow_matches);
  if (bow_matches < options_.min_bow_matches) return std::nullopt;
  std::vector<loop::PointMatch> matches;
  std::vector<std::pair<int, MapPoint*>> pairs;  // new keyframe keypoint -> loop map point
  for (size_t j = 0; j < probe.points.size(); ++j) {
    MapPoint* loop_mp = probe.points[j];
    MapPoint* cur_mp = kf->points[j];
    if (!loop_mp || !cur_mp || cur_mp->bad || loop_mp->bad) continue;
    const int i = loop_mp->index(loop_kf);
    if (i < 0) continue;
    loop::PointMatch m;
    m.p_c1 = loop_kf->T_cw * loop_mp->position;
    m.p_c2 = kf->T_cw * cur_mp->position;
    const cv::KeyPoint& k1 = loop_kf->keypoint(static_cast<size_t>(i));
    const cv::KeyPoint& k2 = kf->keypoint(j);
    m.uv1 = {k1.pt.x, k1.pt.y};
    m.uv2 = {k2.pt.x, k2.pt.y};
    m.sigma2_1 = pyramid_.sigma2[static_cast<size_t>(k1.octave)];
    m.sigma2_2 = pyramid_.sigma2[static_cast<size_t>(k2.octave)];
    matches.push_back(m);
    pairs.emplace_back(static_cast<int>(j), loop_mp);
  }
  loop::Sim3RansacOptions ransac;
  ransac.min_inliers = options_.min_sim3_inliers;
  ransac.fix_scale = metric;
  ransac.seed = options_.seed + ransac_calls_++;
  const auto found = loop::ransacSim3(matches, intrinsics(kf->camera), ransac);
  if (debug)
    std::fprintf(stderr, "    %zu 3D-3D matches, RANSAC inliers %d\n", matches.size(), found ? found->inlier_count : 0);
  if (!found) return std::nullopt;
  Hypothesis h;
  h.S_cur_loop = found->S_21;
  for (size_t k = 0; k < pairs.size(); ++k)
    if (found->inliers[k]) h.matches.push_back(pairs[k]);
  return h;
}

// Metric map only: the new keyframe's pose in the loop keyframe's part of the map from 2D-3D matches (the
// loop keyframe's map points against every keypoint of the new keyframe, by bag of words), EPnP in a
// seeded RANSAC and pose-only optimisation, as relocalisation finds a lost frame's pose. With the scale
// known the loop transform is a rigid pose, which the old points' images fix on their own: this needs no
// triangulated point on the new side, which a keyframe just made on a revisit has few of where the old
// points are (two-lap urban_loop, seed 2: 19-29 3D-3D matches, 167 to 2D).
std::optional<LoopCloser::Hypothesis> LoopCloser::fromImageMatches(KeyFrame* kf, KeyFrame* loop_kf, bool debug) {
  Frame probe(kf->frame_index, kf->timestamp, kf->features);
  probe.feature_vector = kf->feature_vector;
  probe.has_bow = true;
  const int bow_matches = matching::searchByBoW(loop_kf, probe, 0.75f, true);
  if (bow_matches < options_.min_bow_matches) return std::nullopt;
  PnpOptions pnp;
  pnp.seed = options_.seed + ransac_calls_++;
  pnp.threshold_px = 2.45f;  // chi-square 5.991 (2 dof) at level 0
  pnp.min_inliers = options_.min_sim3_inliers;
  pnp.epnp = true;
  const int pnp_inliers = poseFromMatches(probe, kf->camera, pnp);
  int good = 0;
  std::vector<std::pair<int, MapPoint*>> pairs;
  if (pnp_inliers >= 0) {
    std::vector<optimize::PoseObservation> obs;
    for (size_t j = 0; j < probe.points.size(); ++j) {
      if (!probe.points[j]) continue;
      const cv::KeyPoint& kp = kf->keypoint(j);
      obs.push_back({probe.points[j]->position, Eigen::Vector2d(kp.pt.x, kp.pt.y),
                     pyramid_.inv_scale[static_cast<size_t>(kp.octave)]});
      pairs.emplace_back(static_cast<int>(j), probe.points[j]);
    }
    std::vector<bool> outlier;
    good = optimize::optimizePose(kf->camera, obs, probe.T_cw, outlier);
    for (size_t k = pairs.size(); k-- > 0;)
      if (outlier[k]) pairs.erase(pairs.begin() + static_cast<std::ptrdiff_t>(k));
  }
  if (debug)
    std::fprintf(stderr, "    %d BoW matches to keypoints, PnP inliers %d, after pose optimisation %d\n", bow_matches,
                 pnp_inliers, good);
  if (pnp_inliers < 0 || good < options_.min_sim3_inliers) return std::nullopt;
  Hypothesis h;
  h.S_cur_loop = Sim3::fromIsometry(probe.T_cw) * Sim3::fromIsometry(loop_kf->T_cw).inverse();
  h.matches = std::move(pairs);
  return h;
}

bool LoopCloser::process(KeyFrame* kf, bool metric) {
  poses_before_.clear();
  timings_.clear();
  if (kf->bad) return false;
  Clock::time_point t0 = Clock::now();
  const std::vector<KeyFrame*> candidates = detect(kf);
  timings_.emplace_back("loop_query", msSince(t0));
  t0 = Clock::now();
  const bool debug = std::getenv("BESLAM_ORB_DEBUG") != nullptr;
  for (KeyFrame* loop_kf : candidates) {
    if (loop_kf->bad) continue;
    ++stats_.candidates_checked;
    std::optional<Hypothesis> found = fromPointMatches(kf, loop_kf, metric, debug);
    if (!found && metric) found = fromImageMatches(kf, loop_kf, debug);
    if (!found) continue;

    // The new keyframe's pose if the loop is right; the loop neighbourhood projected with it.
    const Sim3 S_cur_loop = found->S_cur_loop;
    const Sim3 S_cw_corrected = S_cur_loop * Sim3::fromIsometry(loop_kf->T_cw);
    std::vector<std::pair<int, MapPoint*>> inliers = std::move(found->matches);
    std::set<int> used;
    for (const auto& [j, mp] : inliers) used.insert(j);
    std::vector<MapPoint*> loop_points;
    std::set<long> seen;
    std::vector<KeyFrame*> loop_neighbourhood = loop_kf->covisibles();
    loop_neighbourhood.push_back(loop_kf);
    for (KeyFrame* n : loop_neighbourhood)
      for (MapPoint* mp : n->validPoints())
        if (seen.insert(mp->id).second) loop_points.push_back(mp);
    const Eigen::Isometry3d T_cw_corrected = S_cw_corrected.toIsometry();
    int projected = 0;
    for (MapPoint* mp : loop_points) {
      if (std::any_of(inliers.begin(), inliers.end(), [&](const auto& p) { return p.second == mp; })) continue;
      const int j = matching::bestKeypointFor(kf, mp, T_cw_corrected, 10.0f, used);
      if (j < 0) continue;
      used.insert(j);
      inliers.emplace_back(j, mp);
      ++projected;
    }
    if (debug) std::fprintf(stderr, "    %zu matches with the projected loop neighbourhood\n", inliers.size());
    if (static_cast<int>(inliers.size()) < options_.min_total_matches) continue;

    // BEV object check: parked cars of the loop keyframe, moved by the loop transform, against the new one's.
    if (options_.object_check) {
      const double radius = metric ? options_.object_radius : options_.object_radius * kf->medianDepth() / 10.0;
      const auto cars_now = parkedCars(kf, map_.objects(), Sim3::fromIsometry(kf->T_cw));
      const auto cars_then = parkedCars(loop_kf, map_.objects(), S_cw_corrected);
      const objects::LayoutCheck check = objects::compareLayouts(
          cars_then, cars_now, {radius, options_.object_max_disagreement, options_.object_min_cars});
      if (debug)
        std::fprintf(stderr, "    BEV object check: %zu parked cars then, %zu now; %s (%d disagree)\n",
                     cars_then.size(), cars_now.size(), check.decided ? "decided" : "undecided", check.disagree);
      if (check.rejected) {
        ++stats_.object_rejections;
        continue;
      }
    }
    timings_.emplace_back("loop_check", msSince(t0));
    t0 = Clock::now();
    const bool closed = close(kf, loop_kf, S_cur_loop, metric, inliers);
    timings_.emplace_back("loop_correct", msSince(t0));
    if (closed) stats_.closures.back().correct_ms = timings_.back().second;
    return closed;
  }
  timings_.emplace_back("loop_check", msSince(t0));
  return false;
}

namespace {

// Fuse: the loop's map points replace the new keyframe's duplicates, then the loop neighbourhood is
// projected into every corrected keyframe (`connected`: the new keyframe and its covisibles). Returns the
// covisibility links the fusion made between a corrected keyframe and one outside them (the loop's links).
std::vector<std::pair<KeyFrame*, KeyFrame*>> fuseLoop(KeyFrame* kf, KeyFrame* loop_kf,
                                                      const std::vector<KeyFrame*>& connected,
                                                      const std::vector<std::pair<int, MapPoint*>>& matches) {
  std::map<long, std::set<long>> links_before;
  for (KeyFrame* k : connected)
    for (KeyFrame* c : k->covisibles()) links_before[k->id].insert(c->id);
  std::vector<MapPoint*> loop_points;
  for (const auto& [j, loop_mp] : matches) {
    MapPoint* loop_point = loop_mp->latest();
    if (loop_point->bad) continue;
    loop_points.push_back(loop_point);
    MapPoint* current = kf->points[static_cast<size_t>(j)];
    if (current && !current->bad) {
      if (current != loop_point) current->replaceWith(loop_point);
    } else if (!loop_point->isIn(kf)) {
      loop_point->addObservation(kf, static_cast<size_t>(j));
      kf->addPoint(loop_point, static_cast<size_t>(j));
    }
  }
  for (KeyFrame* n : loop_kf->covisibles())
    for (MapPoint* mp : n->validPoints()) loop_points.push_back(mp);
  for (KeyFrame* k : connected)
    if (!k->bad) matching::fuse(k, loop_points, 4.0f);
  std::vector<std::pair<KeyFrame*, KeyFrame*>> loop_links;
  for (KeyFrame* k : connected) {
    if (k->bad) continue;
    k->updateConnections();
    for (KeyFrame* c : k->covisibles()) {
      const bool was_linked = links_before[k->id].count(c->id) > 0;
      const bool is_connected = std::find(connected.begin(), connected.end(), c) != connected.end();
      if (!was_linked && !is_connected) loop_links.emplace_back(k, c);
    }
  }
  return loop_links;
}

}  // namespace

bool LoopCloser::close(KeyFrame* kf, KeyFrame* loop_kf, const Sim3& S_cur_loop, bool metric,
                       const std::vector<std::pair<int, MapPoint*>>& matches) {
  // Poses before the correction (the pose graph's measurements) and the corrected start values.
  std::map<long, Sim3> S_before;
  for (KeyFrame* k : map_.keyframes()) {
    S_before[k->id] = Sim3::fromIsometry(k->T_cw);
    poses_before_[k->id] = k->T_cw;
  }
  kf->updateConnections();
  std::vector<KeyFrame*> connected = kf->covisibles();
  connected.push_back(kf);
  const Sim3 S_cw_corrected = S_cur_loop * S_before.at(loop_kf->id);
  std::map<long, Sim3> S_start = S_before;
  std::map<long, KeyFrame*> corrected_by;  // map point id -> the keyframe whose correction moved it
  for (KeyFrame* k : connected) {
    if (k->bad) continue;
    S_start[k->id] = (S_before.at(k->id) * S_before.at(kf->id).inverse()) * S_cw_corrected;
  }
  for (KeyFrame* k : connected) {
    if (k->bad) continue;
    const Sim3 to_corrected = S_start.at(k->id).inverse() * S_before.at(k->id);
    for (MapPoint* mp : k->validPoints())
      if (corrected_by.emplace(mp->id, k).second) mp->position = to_corrected * mp->position;
    k->T_cw = S_start.at(k->id).toIsometry();
  }

  const std::vector<std::pair<KeyFrame*, KeyFrame*>> loop_links = fuseLoop(kf, loop_kf, connected, matches);
  kf->loop_edges.insert(loop_kf);
  loop_kf->loop_edges.insert(kf);

  // Essential graph.
  loop::PoseGraph graph;
  std::map<long, int> node;
  std::vector<KeyFrame*> keyframes;
  for (KeyFrame* k : map_.keyframes()) {
    node[k->id] = static_cast<int>(keyframes.size());
    keyframes.push_back(k);
    graph.S_cw.push_back(S_start.count(k->id) ? S_start.at(k->id) : Sim3::fromIsometry(k->T_cw));
    graph.fixed.push_back(k == loop_kf);
  }
  auto measured = [&](KeyFrame* a, KeyFrame* b) { return S_before.at(a->id) * S_before.at(b->id).inverse(); };
  std::set<std::pair<long, long>> added;
  auto addEdge = [&](KeyFrame* a, KeyFrame* b, const Sim3& S_ab) {
    if (!node.count(a->id) || !node.count(b->id) || a == b) return;
    const auto key = std::minmax(a->id, b->id);
    if (!added.insert(key).second) return;
    graph.edges.push_back({node.at(a->id), node.at(b->id), S_ab, 1.0});
  };
  for (const auto& [a, b] : loop_links)  // the new links hold the corrected relation
    addEdge(
        a, b,
        graph.S_cw[static_cast<size_t>(node.at(a->id))] * graph.S_cw[static_cast<size_t>(node.at(b->id))].inverse());
  for (KeyFrame* k : keyframes) {
    if (k->parent && !k->parent->bad && S_before.count(k->parent->id)) addEdge(k, k->parent, measured(k, k->parent));
    for (KeyFrame* l : k->loop_edges)
      if (!l->bad && S_before.count(l->id)) addEdge(k, l, measured(k, l));
    for (const auto& [c, w] : k->connections())
      if (w >= kCovisibilityEdgeWeight && !c->bad && S_before.count(c->id)) addEdge(k, c, measured(k, c));
  }
  // The new loop edge itself: the corrected relation between the new keyframe and the loop keyframe.
  added.erase(std::minmax(kf->id, loop_kf->id));
  addEdge(kf, loop_kf, S_cw_corrected * S_before.at(loop_kf->id).inverse());
  const loop::PoseGraphResult solved = loop::optimizePoseGraph(graph, options_.pose_graph_iterations, metric);

  for (size_t n = 0; n < keyframes.size(); ++n) keyframes[n]->T_cw = solved.S_cw[n].toIsometry();
  for (MapPoint* mp : map_.points()) {
    const auto it = corrected_by.find(mp->id);
    KeyFrame* ref = it != corrected_by.end() ? it->second : nullptr;
    if (!ref || ref->bad) ref = mp->reference;
    if (!ref || ref->bad || !node.count(ref->id)) {
      ref = nullptr;
      for (const auto& [k, idx] : mp->observations)
        if (!k->bad && node.count(k->id)) {
          ref = k;
          break;
        }
    }
    if (!ref) continue;
    const size_t n = static_cast<size_t>(node.at(ref->id));
    mp->position = solved.S_cw[n].inverse() * (graph.S_cw[n] * mp->position);
    mp->updateNormalAndDepth();
  }
  // Object landmarks follow the keyframe they were last fitted at (a culled one: its next keyframe), as map
  // points follow theirs; left where they were, local BA would pull the corrected keyframes back to them.
  // Landmarks that enter the global BA follow the essential graph's correction first and are then refined
  // with the map; the others follow the whole correction.
  const auto followKeyFrames = [&] {
    map_.objects().followKeyFrames([&](long kf_id) -> std::optional<Eigen::Isometry3d> {
      const KeyFrame* k = map_.keyFrameFrom(kf_id);
      const auto before = k ? poses_before_.find(k->id) : poses_before_.end();
      if (before == poses_before_.end()) return std::nullopt;
      return k->T_cw.inverse() * before->second;
    });
  };
  optimize::BundleAdjustmentOptions ba =
      options_.metric_terms ? options_.metric_terms() : optimize::BundleAdjustmentOptions{};
  ba.solver = options_.global_ba_solver;
  if (!options_.global_ba_objects) {
    ba.object_range_sigma = 0;
    ba.objects.enabled = false;
  }
  const bool objects_in_ba = options_.global_ba_iterations > 0 && ba.objects.enabled;
  if (objects_in_ba) followKeyFrames();
  if (options_.global_ba_iterations > 0) optimize::globalBundleAdjustment(map_, options_.global_ba_iterations, ba);
  if (!objects_in_ba) followKeyFrames();

  LoopClosureEvent event;
  event.keyframe_id = kf->id;
  event.loop_keyframe_id = loop_kf->id;
  event.frame_index = kf->frame_index;
  event.loop_frame_index = loop_kf->frame_index;
  event.matches = static_cast<int>(matches.size());
  const Eigen::Isometry3d& before = poses_before_.at(kf->id);
  event.correction_m = (kf->centre() - before.inverse().translation()).norm();
  event.correction_deg = Eigen::AngleAxisd(kf->T_cw.linear() * before.linear().transpose()).angle() * 180.0 / M_PI;
  event.scale = S_cur_loop.s;
  event.keyframes = static_cast<int>(map_.keyframes().size());
  stats_.closures.push_back(event);
  last_loop_kf_id_ = kf->id;
  groups_.clear();
  return true;
}

}  // namespace beslam::orb
