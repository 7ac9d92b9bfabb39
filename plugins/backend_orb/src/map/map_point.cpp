#include "map/map_point.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include "features/scale_pyramid.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "matching/hamming.hpp"

namespace beslam::orb {
namespace {
std::atomic<long> g_points{0};
}  // namespace

MapPoint::MapPoint(long id_, const Eigen::Vector3d& pos, KeyFrame* ref, Map* map, long first_kf_id)
    : id(id_), position(pos), reference(ref), first_keyframe_id(first_kf_id), map_(map) {
  ++g_points;
}

MapPoint::~MapPoint() { --g_points; }

long MapPoint::instances() { return g_points; }

void MapPoint::addObservation(KeyFrame* kf, size_t idx) { observations.emplace(kf, idx); }

void MapPoint::eraseObservation(KeyFrame* kf) {
  if (observations.erase(kf) == 0) return;
  if (reference == kf && !observations.empty()) reference = observations.begin()->first;
  if (observations.size() <= 2) setBad();
}

bool MapPoint::isIn(const KeyFrame* kf) const { return observations.count(const_cast<KeyFrame*>(kf)) > 0; }

int MapPoint::index(const KeyFrame* kf) const {
  auto it = observations.find(const_cast<KeyFrame*>(kf));
  return it == observations.end() ? -1 : static_cast<int>(it->second);
}

void MapPoint::setBad() {
  if (bad) return;
  bad = true;
  auto obs = std::move(observations);
  observations.clear();
  for (auto& [kf, idx] : obs) kf->erasePoint(idx);
  map_->eraseMapPoint(this);
}

MapPoint* MapPoint::latest() {
  MapPoint* p = this;
  while (p->replaced_by) p = p->replaced_by;
  return p;
}

void MapPoint::replaceWith(MapPoint* other) {
  if (other == this || other == nullptr || bad) return;
  auto obs = std::move(observations);
  observations.clear();
  for (auto& [kf, idx] : obs) {
    if (!other->isIn(kf)) {
      kf->addPoint(other, idx);
      other->addObservation(kf, idx);
    } else {
      kf->erasePoint(idx);
    }
  }
  other->found += found;
  other->visible += visible;
  other->trusted = other->trusted || trusted;
  if (other->object_id < 0) other->object_id = object_id;
  other->computeDistinctiveDescriptor();
  bad = true;
  replaced_by = other;
  map_->eraseMapPoint(this);
}

void MapPoint::computeDistinctiveDescriptor() {
  std::vector<const uint8_t*> descs;
  for (auto& [kf, idx] : observations)
    if (!kf->bad) descs.push_back(kf->features->descriptor(idx));
  if (descs.empty()) return;
  const size_t n = descs.size();
  std::vector<int> dist(n * n, 0);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) dist[i * n + j] = dist[j * n + i] = hamming(descs[i], descs[j]);
  int best_median = 1 << 30;
  size_t best = 0;
  std::vector<int> row(n);
  for (size_t i = 0; i < n; ++i) {
    std::copy(dist.begin() + i * n, dist.begin() + (i + 1) * n, row.begin());
    std::nth_element(row.begin(), row.begin() + (n - 1) / 2, row.end());
    const int median = row[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  std::copy(descs[best], descs[best] + 32, descriptor.begin());
}

void MapPoint::completeNewPoint(const std::array<uint8_t, 3>& bgr) {
  b = bgr[0];
  g = bgr[1];
  r = bgr[2];
  grey = static_cast<uint8_t>((bgr[0] + bgr[1] + bgr[2]) / 3);
  computeDistinctiveDescriptor();
  updateNormalAndDepth();
}

void MapPoint::updateNormalAndDepth() {
  if (observations.empty() || reference == nullptr) return;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  int count = 0;
  for (auto& [kf, idx] : observations) {
    Eigen::Vector3d d = position - kf->centre();
    const double norm = d.norm();
    if (norm > 0) {
      n += d / norm;
      ++count;
    }
  }
  if (count > 0) normal = n / count;
  const int idx = index(reference);
  if (idx < 0) return;
  const double dist = (position - reference->centre()).norm();
  const int level = reference->keypoint(idx).octave;
  const ScalePyramid& pyr = reference->pyramid;
  max_distance = static_cast<float>(dist * pyr.scale[level]);
  min_distance = static_cast<float>(max_distance / pyr.scale[pyr.levels - 1]);
}

int MapPoint::predictLevel(double distance, const ScalePyramid& pyramid) const {
  const double ratio = max_distance / std::max(distance, 1e-9);
  int level = static_cast<int>(std::ceil(std::log(ratio) / pyramid.log_factor));
  return std::clamp(level, 0, pyramid.levels - 1);
}

}  // namespace beslam::orb
