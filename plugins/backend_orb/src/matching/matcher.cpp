#include "matching/matcher.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core/utility.hpp>

#include "map/camera_model.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map_point.hpp"
#include "matching/hamming.hpp"

namespace beslam::orb::matching {

namespace {

// The nearest and second-nearest descriptor distances among a query's candidates, with the nearest one's
// index and the pyramid levels of both (for the same-level ratio test of local-map search).
struct NearestTwo {
  int best = 256, second = 256, index = -1, best_level = -1, second_level = -1;
  void add(int distance, int candidate, int level = -1) {
    if (distance < best) {
      second = best;
      second_level = best_level;
      best = distance;
      best_level = level;
      index = candidate;
    } else if (distance < second) {
      second = distance;
      second_level = level;
    }
  }
};

}  // namespace

void RotationHistogram::add(float angle1, float angle2, int id) {
  float rot = angle1 - angle2;
  if (rot < 0) rot += 360.f;
  const float bin_width = 360.f / kHistogramBins;
  const int bin = static_cast<int>(std::floor(rot / bin_width + 0.5f)) % kHistogramBins;
  bins_[bin].push_back(id);
}

std::vector<int> RotationHistogram::rejected() const {
  int m[3] = {-1, -1, -1};
  size_t c[3] = {0, 0, 0};
  for (int i = 0; i < kHistogramBins; ++i) {
    const size_t s = bins_[i].size();
    if (s > c[0]) {
      c[2] = c[1];
      m[2] = m[1];
      c[1] = c[0];
      m[1] = m[0];
      c[0] = s;
      m[0] = i;
    } else if (s > c[1]) {
      c[2] = c[1];
      m[2] = m[1];
      c[1] = s;
      m[1] = i;
    } else if (s > c[2]) {
      c[2] = s;
      m[2] = i;
    }
  }
  // Weak second and third bins (under a tenth of the first) are not kept.
  if (c[1] < 0.1 * c[0]) {
    m[1] = -1;
    m[2] = -1;
  }
  if (c[2] < 0.1 * c[0]) m[2] = -1;
  std::vector<int> out;
  for (int i = 0; i < kHistogramBins; ++i) {
    if (i == m[0] || i == m[1] || i == m[2]) continue;
    out.insert(out.end(), bins_[i].begin(), bins_[i].end());
  }
  return out;
}

int searchForInitialization(const FeatureSet& f1, const FeatureSet& f2, std::vector<cv::Point2f>& prev_matched,
                            std::vector<int>& matches12, int window, float ratio, int max_level) {
  matches12.assign(f1.size(), -1);
  std::vector<int> dist21(f2.size(), std::numeric_limits<int>::max());
  std::vector<int> matches21(f2.size(), -1);
  RotationHistogram hist;
  int n = 0;
  for (size_t i1 = 0; i1 < f1.size(); ++i1) {
    const cv::KeyPoint& kp1 = f1.keypoints[i1];
    if (kp1.octave > max_level) continue;
    const auto cand =
        f2.query(prev_matched[i1].x, prev_matched[i1].y, static_cast<float>(window), kp1.octave, kp1.octave);
    NearestTwo nn;
    const uint8_t* d1 = f1.descriptor(i1);
    for (int i2 : cand) {
      const int d = hamming(d1, f2.descriptor(i2));
      if (dist21[i2] <= d) continue;
      nn.add(d, i2);
    }
    if (nn.index < 0 || nn.best > kThLow || nn.best >= ratio * nn.second) continue;
    if (matches21[nn.index] >= 0) {  // a previous, worse match loses the keypoint
      matches12[matches21[nn.index]] = -1;
      --n;
    }
    matches12[i1] = nn.index;
    matches21[nn.index] = static_cast<int>(i1);
    dist21[nn.index] = nn.best;
    ++n;
  }
  for (size_t i1 = 0; i1 < f1.size(); ++i1)
    if (matches12[i1] >= 0) hist.add(f1.keypoints[i1].angle, f2.keypoints[matches12[i1]].angle, static_cast<int>(i1));
  for (int i1 : hist.rejected()) {
    if (matches12[i1] >= 0) {
      matches12[i1] = -1;
      --n;
    }
  }
  for (size_t i1 = 0; i1 < f1.size(); ++i1)
    if (matches12[i1] >= 0) prev_matched[i1] = f2.keypoints[matches12[i1]].pt;
  return n;
}

int searchByProjection(Frame& cur, const Frame& last, const Camera& camera, const ScalePyramid& pyramid, float th) {
  const FeatureSet& f = *cur.features;
  RotationHistogram hist;
  int n = 0;
  for (size_t i = 0; i < last.size(); ++i) {
    MapPoint* mp = last.points[i];
    if (!mp || last.outlier[i] || mp->bad) continue;
    const Eigen::Vector3d pc = cur.T_cw * mp->position;
    if (pc.z() <= 0) continue;
    const Eigen::Vector2d uv = project(camera, pc);
    if (!inImage(camera, uv.x(), uv.y())) continue;
    const int octave = last.features->keypoints[i].octave;
    const float radius = th * static_cast<float>(pyramid.scale[octave]);
    const auto cand = f.query(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius, std::max(octave - 1, 0),
                              std::min(octave + 1, pyramid.levels - 1));
    NearestTwo nn;
    for (int j : cand) {
      if (cur.points[j] && cur.points[j]->numObservations() > 0) continue;
      const int d = hamming(mp->descriptor.data(), f.descriptor(j));
      nn.add(d, j);
    }
    if (nn.index < 0 || nn.best > kThHigh) continue;
    cur.points[nn.index] = mp;
    cur.outlier[nn.index] = false;
    ++n;
    hist.add(last.features->keypoints[i].angle, f.keypoints[nn.index].angle, nn.index);
  }
  for (int j : hist.rejected()) {
    if (cur.points[j]) {
      cur.points[j] = nullptr;
      --n;
    }
  }
  return n;
}

int searchLocalPoints(Frame& cur, const std::vector<MapPoint*>& points, const ScalePyramid& pyramid, float th,
                      float ratio) {
  const FeatureSet& f = *cur.features;
  int n = 0;
  for (MapPoint* mp : points) {
    if (!mp->track_in_view || mp->bad) continue;
    const int level = mp->track_level;
    const float r = th * (mp->track_view_cos > 0.998f ? 2.5f : 4.0f) * static_cast<float>(pyramid.scale[level]);
    const auto cand = f.query(mp->track_u, mp->track_v, r, std::max(level - 1, 0), level);
    NearestTwo nn;
    for (int j : cand) {
      if (cur.points[j] && cur.points[j]->numObservations() > 0) continue;
      const int d = hamming(mp->descriptor.data(), f.descriptor(j));
      nn.add(d, j, f.keypoints[j].octave);
    }
    if (nn.index < 0 || nn.best > kThHigh) continue;
    if (nn.best_level == nn.second_level && nn.best > ratio * nn.second) continue;
    cur.points[nn.index] = mp;
    cur.outlier[nn.index] = false;
    ++n;
  }
  return n;
}

int searchByProjectionWide(Frame& cur, const std::vector<MapPoint*>& points, const Eigen::Isometry3d& T_cw,
                           const Camera& camera, const ScalePyramid& pyramid, float radius, float ratio,
                           int max_distance) {
  const FeatureSet& f = *cur.features;
  std::vector<int> best_dist(f.size(), 256);
  RotationHistogram hist;
  const Eigen::Vector3d centre = T_cw.inverse().translation();
  for (MapPoint* mp : points) {
    if (!mp || mp->bad) continue;
    const Eigen::Vector3d pc = T_cw * mp->position;
    if (pc.z() <= 0) continue;
    const Eigen::Vector2d uv = project(camera, pc);
    if (!inImage(camera, uv.x(), uv.y())) continue;
    const double dist = (mp->position - centre).norm();
    if (dist < 0.5 * mp->min_distance || dist > 2.0 * mp->max_distance) continue;
    const int level = mp->predictLevel(dist, pyramid);
    const auto cand = f.query(static_cast<float>(uv.x()), static_cast<float>(uv.y()),
                              radius * static_cast<float>(pyramid.scale[level]), std::max(level - 2, 0),
                              std::min(level + 2, pyramid.levels - 1));
    NearestTwo nn;
    for (int j : cand) {
      const int d = hamming(mp->descriptor.data(), f.descriptor(j));
      nn.add(d, j);
    }
    if (nn.index < 0 || nn.best > max_distance || nn.best > ratio * nn.second) continue;
    if (nn.best >= best_dist[nn.index]) continue;
    best_dist[nn.index] = nn.best;
    cur.points[nn.index] = mp;
    cur.outlier[nn.index] = false;
  }
  int n = 0;
  for (size_t j = 0; j < f.size(); ++j) {
    if (!cur.points[j]) continue;
    const int i = cur.points[j]->index(cur.points[j]->reference);
    const float angle_ref = i >= 0 ? cur.points[j]->reference->keypoint(i).angle : f.keypoints[j].angle;
    hist.add(angle_ref, f.keypoints[j].angle, static_cast<int>(j));
    ++n;
  }
  for (int j : hist.rejected()) {
    cur.points[j] = nullptr;
    --n;
  }
  return n;
}

int searchByBoW(const KeyFrame* kf, Frame& cur, float ratio, bool check_orientation) {
  const FeatureSet& fk = *kf->features;
  const FeatureSet& f = *cur.features;
  std::vector<int> matched_from(f.size(), -1);  // kf keypoint index per frame keypoint
  RotationHistogram hist;
  int n = 0;
  auto ki = kf->feature_vector.begin();
  auto fi = cur.feature_vector.begin();
  while (ki != kf->feature_vector.end() && fi != cur.feature_vector.end()) {
    if (ki->first < fi->first) {
      ki = kf->feature_vector.lower_bound(fi->first);
      continue;
    }
    if (fi->first < ki->first) {
      fi = cur.feature_vector.lower_bound(ki->first);
      continue;
    }
    for (int ik : ki->second) {
      MapPoint* mp = kf->points[ik];
      if (!mp || mp->bad) continue;
      const uint8_t* dk = fk.descriptor(ik);
      NearestTwo nn;
      for (int j : fi->second) {
        if (cur.points[j]) continue;
        nn.add(hamming(dk, f.descriptor(j)), j);
      }
      if (nn.index < 0 || nn.best > kThLow || nn.best >= ratio * nn.second) continue;
      cur.points[nn.index] = mp;
      cur.outlier[nn.index] = false;
      matched_from[nn.index] = ik;
      if (check_orientation) hist.add(fk.keypoints[ik].angle, f.keypoints[nn.index].angle, nn.index);
      ++n;
    }
    ++ki;
    ++fi;
  }
  if (check_orientation)
    for (int j : hist.rejected()) {
      if (cur.points[j] && matched_from[j] >= 0) {
        cur.points[j] = nullptr;
        --n;
      }
    }
  return n;
}

namespace {

// Each keypoint's direct-index (bag of words) node.
std::vector<uint32_t> directIndexNodes(const KeyFrame* kf) {
  std::vector<uint32_t> node(kf->features->size(), 0);
  for (const auto& [id, idx] : kf->feature_vector)
    for (int i : idx) node[i] = id;
  return node;
}

// searchForTriangulation's search: each keypoint of kf1 (without a map point) looks for its nearest two
// descriptors among kf2's keypoints (without one) near its epipolar line, on the segment of it that kf1's
// map points' depths allow, away from the epipole.
class EpipolarSearch {
 public:
  EpipolarSearch(const KeyFrame* kf1, const KeyFrame* kf2, const Eigen::Matrix3d& F21)
      : kf1_(kf1),
        kf2_(kf2),
        f1_(*kf1->features),
        f2_(*kf2->features),
        cam_(kf2->camera),
        pyr_(kf2->pyramid),
        F21_(F21),
        T21_(kf2->T_cw * kf1->T_cw.inverse()),
        c1_in_2_(T21_.translation()) {}

  // Only pairs with the same direct-index node (empty: no restriction).
  void restrictToNodes(std::vector<uint32_t> node1, std::vector<uint32_t> node2) {
    node1_ = std::move(node1);
    node2_ = std::move(node2);
  }
  // Epipole in kf2 and the depth range along kf1's rays worth searching; false when there is none (kf1's
  // centre in kf2's focal plane, or no map point of kf1 in front of it).
  bool findEpipoleAndDepths();
  void collectCandidates();
  // Every keypoint's nearest two (none for those with a map point).
  std::vector<NearestTwo> nearestForAll() const;

 private:
  struct Box {
    double x_lo, x_hi, y_lo, y_hi;
  };
  // One keypoint of kf1's epipolar line in kf2 (ln: the norm of its normal).
  struct Line {
    int i1;
    Eigen::Vector3d line;
    double ln;
    const uint8_t* descriptor;
  };
  NearestTwo nearestAlongLine(int i1, std::vector<int>& stamp, std::vector<int>& near) const;
  bool segmentBox(const cv::KeyPoint& kp1, Box& box) const;
  void searchCells(const Line& l, int gr, int gc0, int gc1, std::vector<int>& stamp, std::vector<int>& near,
                   NearestTwo& nn) const;

  const KeyFrame* kf1_;
  const KeyFrame* kf2_;
  const FeatureSet& f1_;
  const FeatureSet& f2_;
  const Camera& cam_;
  const ScalePyramid& pyr_;
  const Eigen::Matrix3d& F21_;
  const Eigen::Isometry3d T21_;
  const Eigen::Vector3d c1_in_2_;
  std::vector<uint32_t> node1_, node2_;
  Eigen::Vector2d epipole_;
  double d_min_ = std::numeric_limits<double>::max(), d_max_ = 0, band_max_ = 0;
  float cell_h_ = 0;

  // kf2's keypoints without a point, copied once into grid order (a cell's keypoints are contiguous) with
  // their tests' thresholds: positions and line thresholds in arrays of their own (a cell range is screened
  // in one branch-free pass), the epipole threshold and kf2 index per candidate. The candidates are visited
  // as before (cell by cell, increasing index within a cell), so the matches are the same.
  struct Candidate {
    double epipole_th;  // 100 x its level's scale: squared distance to the epipole, px^2
    int index;          // in kf2
  };
  std::vector<Candidate> c2_;
  std::vector<double> c2_x_, c2_y_, c2_line_th_;  // c2_line_th_: 3.84 sigma^2 of its level, squared px to the line
  std::vector<int> cell_start_;
};

bool EpipolarSearch::findEpipoleAndDepths() {
  if (c1_in_2_.z() <= 1e-9 && c1_in_2_.z() >= -1e-9) return false;
  epipole_ = project(cam_, c1_in_2_);
  for (MapPoint* mp : kf1_->points) {
    if (!mp || mp->bad) continue;
    const double z = (kf1_->T_cw * mp->position).z();
    if (z <= 0) continue;
    d_min_ = std::min(d_min_, z);
    d_max_ = std::max(d_max_, z);
  }
  if (d_max_ <= 0) return false;
  d_min_ *= 0.5;
  d_max_ *= 2.0;
  band_max_ = std::sqrt(3.84 * pyr_.sigma2[pyr_.levels - 1]);
  cell_h_ = static_cast<float>(cam_.height) / FeatureGrid::kRows;
  return true;
}

void EpipolarSearch::collectCandidates() {
  c2_.reserve(f2_.size());
  c2_x_.reserve(f2_.size());
  c2_y_.reserve(f2_.size());
  c2_line_th_.reserve(f2_.size());
  cell_start_.assign(FeatureGrid::kCols * FeatureGrid::kRows + 1, 0);
  for (int cell = 0; cell < FeatureGrid::kCols * FeatureGrid::kRows; ++cell) {
    cell_start_[cell] = static_cast<int>(c2_.size());
    for (const int *it = f2_.grid.cellBegin(cell), *end = f2_.grid.cellEnd(cell); it != end; ++it) {
      if (kf2_->points[*it]) continue;
      const cv::KeyPoint& kp2 = f2_.keypoints[*it];
      c2_.push_back({100.0 * pyr_.scale[kp2.octave], *it});
      c2_x_.push_back(kp2.pt.x);
      c2_y_.push_back(kp2.pt.y);
      c2_line_th_.push_back(3.84 * pyr_.sigma2[kp2.octave]);
    }
  }
  cell_start_.back() = static_cast<int>(c2_.size());
}

// Each keypoint of kf1 finds its nearest two along its line independently of the others: in parallel
// (OpenCV's thread pool, a few stripes, each with its own visit stamps), into its own slot. Which one
// keeps a contested keypoint of kf2 is decided afterwards in index order, as in one sequential pass, so
// the matches do not depend on the threads.
std::vector<NearestTwo> EpipolarSearch::nearestForAll() const {
  std::vector<NearestTwo> nearest(f1_.size());
  auto searchRange = [&](const cv::Range& range) {
    std::vector<int> stamp(c2_.size(), -1);  // by position in c2_
    std::vector<int> near(c2_.size());       // a cell range's candidates near the line
    for (int i1 = range.start; i1 < range.end; ++i1)
      if (!kf1_->points[i1]) nearest[i1] = nearestAlongLine(i1, stamp, near);
  };
  cv::parallel_for_(cv::Range(0, static_cast<int>(f1_.size())), searchRange, 4);
  return nearest;
}

// The box of the segment of kp1's line between the depths d_min and d_max on kf1's ray, widened by the
// widest band and clipped to the image; false when it is empty.
bool EpipolarSearch::segmentBox(const cv::KeyPoint& kp1, Box& box) const {
  const Eigen::Vector3d ray = T21_.linear() * unproject(cam_, kp1.pt.x, kp1.pt.y);
  double a = d_min_, b = d_max_;
  const double z_a = c1_in_2_.z() + ray.z() * a, z_b = c1_in_2_.z() + ray.z() * b;
  const double z_eps = 1e-3 * d_min_;
  if (z_a <= z_eps && z_b <= z_eps) return false;
  if (z_a <= z_eps) a = (z_eps - c1_in_2_.z()) / ray.z();
  if (z_b <= z_eps) b = (z_eps - c1_in_2_.z()) / ray.z();
  const Eigen::Vector2d pa = project(cam_, c1_in_2_ + ray * a), pb = project(cam_, c1_in_2_ + ray * b);
  box.x_lo = std::max(0.0, std::min(pa.x(), pb.x()) - band_max_);
  box.x_hi = std::min(cam_.width - 1.0, std::max(pa.x(), pb.x()) + band_max_);
  box.y_lo = std::max(0.0, std::min(pa.y(), pb.y()) - band_max_);
  box.y_hi = std::min(cam_.height - 1.0, std::max(pa.y(), pb.y()) + band_max_);
  return !(box.x_lo > box.x_hi || box.y_lo > box.y_hi);
}

NearestTwo EpipolarSearch::nearestAlongLine(int i1, std::vector<int>& stamp, std::vector<int>& near) const {
  NearestTwo nn;
  const cv::KeyPoint& kp1 = f1_.keypoints[i1];
  const Eigen::Vector3d x1(kp1.pt.x, kp1.pt.y, 1.0);
  const Eigen::Vector3d line = F21_ * x1;
  const double ln = std::hypot(line.x(), line.y());
  if (ln < 1e-12) return nn;
  Box box;
  if (!segmentBox(kp1, box)) return nn;

  // The epipolar test first, on the contiguous array; descriptors only for what passes it.
  const Line l{i1, line, ln, f1_.descriptor(i1)};
  const int row0 = static_cast<int>(box.y_lo / cell_h_), row1 = static_cast<int>(box.y_hi / cell_h_);
  for (int row = row0; row <= row1; ++row) {
    const double ry0 = std::max(box.y_lo, row * static_cast<double>(cell_h_));
    const double ry1 = std::min(box.y_hi, (row + 1) * static_cast<double>(cell_h_) - 1e-3);
    double xa = box.x_lo, xb = box.x_hi;
    if (std::fabs(line.x()) > 1e-9) {  // x of the line at both row edges, widened by the band
      const double xr0 = -(line.y() * ry0 + line.z()) / line.x();
      const double xr1 = -(line.y() * ry1 + line.z()) / line.x();
      const double widen = band_max_ * ln / std::fabs(line.x());
      xa = std::max(box.x_lo, std::min(xr0, xr1) - widen);
      xb = std::min(box.x_hi, std::max(xr0, xr1) + widen);
    }
    if (xa > xb) continue;
    int gc0, gc1, gr0, gr1;
    if (!f2_.grid.cellRange(static_cast<float>(xa), static_cast<float>(ry0), static_cast<float>(xb),
                            static_cast<float>(ry1), gc0, gc1, gr0, gr1))
      continue;
    for (int gr = gr0; gr <= gr1; ++gr) searchCells(l, gr, gc0, gc1, stamp, near, nn);
  }
  return nn;
}

// The cells gc0..gc1 of grid row gr are contiguous in c2_: the line test over all of them first (no branch
// per candidate), then the rest for the ones near the line, in the same order. A candidate failing the
// line test fails it again whenever this keypoint's search meets it, so only the ones passing it need the
// visit stamp.
void EpipolarSearch::searchCells(const Line& l, int gr, int gc0, int gc1, std::vector<int>& stamp,
                                 std::vector<int>& near, NearestTwo& nn) const {
  const double ln2 = l.ln * l.ln;
  const double lx = l.line.x(), ly = l.line.y(), lz = l.line.z();
  const int b = cell_start_[gr * FeatureGrid::kCols + gc0], e = cell_start_[gr * FeatureGrid::kCols + gc1 + 1];
  int n_near = 0;
  for (int k = b; k < e; ++k) {
    const double dl = lx * c2_x_[k] + ly * c2_y_[k] + lz;
    near[n_near] = k;
    n_near += !(dl * dl / ln2 >= c2_line_th_[k]);
  }
  for (int j = 0; j < n_near; ++j) {
    const int k = near[j];
    if (stamp[k] == l.i1) continue;
    stamp[k] = l.i1;
    const Candidate& c = c2_[k];
    const double ex = epipole_.x() - c2_x_[k], ey = epipole_.y() - c2_y_[k];
    if (ex * ex + ey * ey < c.epipole_th) continue;
    const int i2 = c.index;
    if (!node2_.empty() && node2_[i2] != node1_[l.i1]) continue;  // triangulation_bow
    nn.add(hamming(l.descriptor, f2_.descriptor(i2)), i2);
  }
}

// kf2's keypoint for each of kf1's (-1: none): the nearest passing the ratio test; a keypoint of kf2 that
// several found goes to the nearest of them (the first in index order among equals).
std::vector<int> keepNearestMatches(const std::vector<NearestTwo>& nearest, size_t n2, float ratio) {
  std::vector<int> matched2(n2, -1), dist2(n2, 256);
  std::vector<int> match12(nearest.size(), -1);
  for (size_t i1 = 0; i1 < nearest.size(); ++i1) {
    const NearestTwo& nn = nearest[i1];
    if (nn.index < 0 || nn.best > kThLow || nn.best > ratio * nn.second) continue;
    if (matched2[nn.index] >= 0) {
      if (dist2[nn.index] <= nn.best) continue;
      match12[matched2[nn.index]] = -1;
    }
    matched2[nn.index] = static_cast<int>(i1);
    dist2[nn.index] = nn.best;
    match12[i1] = nn.index;
  }
  return match12;
}

// Drops the matches whose keypoints' rotation falls outside the three main bins of the histogram.
void dropRotationOutliers(const FeatureSet& f1, const FeatureSet& f2, std::vector<int>& match12) {
  RotationHistogram hist;
  for (size_t i1 = 0; i1 < f1.size(); ++i1)
    if (match12[i1] >= 0) hist.add(f1.keypoints[i1].angle, f2.keypoints[match12[i1]].angle, static_cast<int>(i1));
  for (int i1 : hist.rejected()) match12[i1] = -1;
}

}  // namespace

int searchForTriangulation(const KeyFrame* kf1, const KeyFrame* kf2, const Eigen::Matrix3d& F21,
                           std::vector<std::pair<int, int>>& matches, float ratio, bool check_orientation,
                           bool same_bow_node) {
  matches.clear();
  const FeatureSet& f1 = *kf1->features;
  const FeatureSet& f2 = *kf2->features;
  EpipolarSearch search(kf1, kf2, F21);
  if (same_bow_node && !kf1->feature_vector.empty() && !kf2->feature_vector.empty())
    search.restrictToNodes(directIndexNodes(kf1), directIndexNodes(kf2));
  if (!search.findEpipoleAndDepths()) return 0;
  search.collectCandidates();
  std::vector<int> match12 = keepNearestMatches(search.nearestForAll(), f2.size(), ratio);
  if (check_orientation) dropRotationOutliers(f1, f2, match12);
  for (size_t i1 = 0; i1 < f1.size(); ++i1)
    if (match12[i1] >= 0) matches.emplace_back(static_cast<int>(i1), match12[i1]);
  return static_cast<int>(matches.size());
}

int bestKeypointFor(const KeyFrame* kf, const MapPoint* mp, const Eigen::Isometry3d& T_cw, float th,
                    const std::set<int>& taken) {
  const FeatureSet& f = *kf->features;
  const Camera& cam = kf->camera;
  const ScalePyramid& pyr = kf->pyramid;
  const Eigen::Vector3d pc = T_cw * mp->position;
  if (pc.z() <= 0) return -1;
  const Eigen::Vector2d uv = project(cam, pc);
  if (!inImage(cam, uv.x(), uv.y())) return -1;
  const Eigen::Vector3d po = mp->position - T_cw.inverse().translation();
  const double dist = po.norm();
  if (dist < 0.8 * mp->min_distance || dist > 1.2 * mp->max_distance) return -1;
  if (po.dot(mp->normal) < 0.5 * dist) return -1;
  const int level = mp->predictLevel(dist, pyr);
  const float radius = th * static_cast<float>(pyr.scale[level]);
  NearestTwo nn;
  for (int j : f.query(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius)) {
    const cv::KeyPoint& kp = f.keypoints[j];
    if (kp.octave < level - 1 || kp.octave > level || taken.count(j)) continue;
    const double ex = uv.x() - kp.pt.x, ey = uv.y() - kp.pt.y;
    if ((ex * ex + ey * ey) * pyr.inv_sigma2[kp.octave] > 5.99) continue;
    nn.add(hamming(mp->descriptor.data(), f.descriptor(j)), j);
  }
  return nn.index >= 0 && nn.best <= kThLow ? nn.index : -1;
}

int fuse(KeyFrame* kf, const std::vector<MapPoint*>& points, float th) {
  int n = 0;
  for (MapPoint* mp : points) {
    if (!mp || mp->bad || mp->isIn(kf)) continue;
    const int j = bestKeypointFor(kf, mp, kf->T_cw, th);
    if (j < 0) continue;
    MapPoint* existing = kf->points[static_cast<size_t>(j)];
    if (existing && !existing->bad) {
      if (existing->numObservations() > mp->numObservations())
        mp->replaceWith(existing);
      else
        existing->replaceWith(mp);
    } else {
      mp->addObservation(kf, static_cast<size_t>(j));
      kf->addPoint(mp, static_cast<size_t>(j));
    }
    ++n;
  }
  return n;
}

}  // namespace beslam::orb::matching
