#include "map/keyframe.hpp"

#include <algorithm>
#include <atomic>

#include "map/frame.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"

namespace beslam::orb {
namespace {
std::atomic<long> g_keyframes{0};
}  // namespace

KeyFrame::KeyFrame(long id_, const Frame& frame, const Camera& cam, const ScalePyramid& pyr, Map* map)
    : id(id_),
      frame_index(frame.index),
      timestamp(frame.timestamp),
      features(frame.features),
      camera(cam),
      pyramid(pyr),
      T_cw(frame.T_cw),
      points(frame.points),
      bow(frame.bow),
      feature_vector(frame.feature_vector),
      map_(map) {
  ++g_keyframes;
  // Tracking outliers stay out (ORB-SLAM2 passes them on for BA to judge; measured worse here).
  for (size_t i = 0; i < points.size(); ++i)
    if (points[i] && (frame.outlier[i] || points[i]->bad)) points[i] = nullptr;
}

KeyFrame::~KeyFrame() { --g_keyframes; }

long KeyFrame::instances() { return g_keyframes; }

void KeyFrame::erasePoint(MapPoint* mp) {
  const int idx = mp->index(this);
  if (idx >= 0) points[idx] = nullptr;
}

std::vector<MapPoint*> KeyFrame::validPoints() const {
  std::vector<MapPoint*> out;
  for (MapPoint* mp : points)
    if (mp && !mp->bad) out.push_back(mp);
  return out;
}

int KeyFrame::trackedPoints(int min_observations) const {
  int n = 0;
  for (MapPoint* mp : points)
    if (mp && !mp->bad && mp->numObservations() >= min_observations) ++n;
  return n;
}

double KeyFrame::medianDepth(int q) const {
  std::vector<double> depths;
  const Eigen::Vector3d r2 = T_cw.linear().row(2).transpose();
  const double t2 = T_cw.translation().z();
  for (MapPoint* mp : points)
    if (mp && !mp->bad) depths.push_back(r2.dot(mp->position) + t2);
  if (depths.empty()) return -1;
  const size_t k = (depths.size() - 1) / q;
  std::nth_element(depths.begin(), depths.begin() + k, depths.end());
  return depths[k];
}

void KeyFrame::addConnection(KeyFrame* kf, int w) {
  auto it = weights_.find(kf);
  if (it != weights_.end() && it->second == w) return;
  weights_[kf] = w;
  sortConnections();
}

void KeyFrame::eraseConnection(KeyFrame* kf) {
  if (weights_.erase(kf)) sortConnections();
}

void KeyFrame::sortConnections() {
  std::vector<std::pair<int, KeyFrame*>> v;
  for (auto& [kf, w] : weights_) v.emplace_back(w, kf);
  std::stable_sort(v.begin(), v.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second->id < b.second->id;
  });
  ordered_.clear();
  for (auto& p : v) ordered_.push_back(p.second);
}

std::vector<KeyFrame*> KeyFrame::bestCovisibles(int n) const {
  if (static_cast<int>(ordered_.size()) <= n) return ordered_;
  return std::vector<KeyFrame*>(ordered_.begin(), ordered_.begin() + n);
}

int KeyFrame::weight(KeyFrame* kf) const {
  auto it = weights_.find(kf);
  return it == weights_.end() ? 0 : it->second;
}

void KeyFrame::updateConnections() {
  std::map<KeyFrame*, int, IdLess<KeyFrame>> counter;
  for (MapPoint* mp : points) {
    if (!mp || mp->bad) continue;
    for (auto& [kf, idx] : mp->observations)
      if (kf != this && !kf->bad) ++counter[kf];
  }
  if (counter.empty()) return;
  constexpr int kThreshold = 15;
  KeyFrame* best = nullptr;
  int best_w = 0;
  std::map<KeyFrame*, int, IdLess<KeyFrame>> kept;
  for (auto& [kf, w] : counter) {
    if (w > best_w) {
      best_w = w;
      best = kf;
    }
    if (w >= kThreshold) {
      kept[kf] = w;
      kf->addConnection(this, w);
    }
  }
  if (kept.empty()) {
    kept[best] = best_w;
    best->addConnection(this, best_w);
  }
  // Links that fell below the threshold disappear on both sides.
  for (auto& [kf, w] : weights_)
    if (!kept.count(kf)) kf->eraseConnection(this);
  weights_ = std::move(kept);
  sortConnections();
  if (first_connection_ && this != map_->origin() && !ordered_.empty()) {
    parent = ordered_.front();
    parent->children.insert(this);
    first_connection_ = false;
  }
}

void KeyFrame::restoreLinks(KeyFrame* parent_kf, const std::map<KeyFrame*, int, IdLess<KeyFrame>>& weights) {
  weights_ = weights;
  sortConnections();
  parent = parent_kf;
  if (parent) parent->children.insert(this);
  first_connection_ = parent == nullptr;
}

void KeyFrame::setBad() {
  // The origin and keyframes that closed a loop (their loop edges hold the essential graph) stay, as in ORB-SLAM2.
  if (this == map_->origin() || bad || !loop_edges.empty()) return;
  for (auto& [kf, w] : weights_) kf->eraseConnection(this);
  for (size_t i = 0; i < points.size(); ++i) {
    MapPoint* mp = points[i];
    if (mp && !mp->bad) {
      points[i] = nullptr;
      mp->eraseObservation(this);
    }
  }
  weights_.clear();
  ordered_.clear();

  // Re-parent the children: repeatedly attach the child with the strongest link to a keyframe that
  // is already a candidate parent (starting from our own parent), which then becomes one too.
  std::set<KeyFrame*, IdLess<KeyFrame>> candidates;
  if (parent) candidates.insert(parent);
  while (!children.empty()) {
    KeyFrame* best_child = nullptr;
    KeyFrame* best_parent = nullptr;
    int best_w = -1;
    for (KeyFrame* child : children) {
      if (child->bad) continue;
      for (KeyFrame* cand : child->covisibles()) {
        if (!candidates.count(cand)) continue;
        const int w = child->weight(cand);
        if (w > best_w) {
          best_w = w;
          best_child = child;
          best_parent = cand;
        }
      }
    }
    if (!best_child) break;
    best_child->parent = best_parent;
    best_parent->children.insert(best_child);
    candidates.insert(best_child);
    children.erase(best_child);
  }
  for (KeyFrame* child : children) {  // no covisible candidate: attach to our parent
    child->parent = parent;
    if (parent) parent->children.insert(child);
  }
  children.clear();
  if (parent) {
    parent->children.erase(this);
    T_cp = T_cw * parent->T_cw.inverse();
  }
  bad = true;
  map_->eraseKeyFrame(this);
}

}  // namespace beslam::orb
