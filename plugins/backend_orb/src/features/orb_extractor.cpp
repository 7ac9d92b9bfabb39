#include "features/orb_extractor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace beslam::orb {
namespace {

constexpr int kHalfPatch = 15;

}  // namespace

OrbExtractor::OrbExtractor(const ExtractorOptions& options)
    : options_(options), pyramid_(options.levels, options.scale_factor) {
  if (options.border < kIcRowOffset)  // the orientation patch's rows are read 16 px either side of a corner
    throw std::invalid_argument("OrbExtractor: border must be at least " + std::to_string(kIcRowOffset) + " px");
  // Half-width of a disc of radius 15 at each row offset v (symmetric by construction).
  umax_.resize(kHalfPatch + 1);
  for (int v = 0; v <= kHalfPatch; ++v)
    umax_[v] = static_cast<int>(std::floor(std::sqrt(kHalfPatch * kHalfPatch - v * v + 0.5)));
  for (int r = 0; r < kIcRows; ++r) {
    const int d = umax_[std::abs(r - kHalfPatch)];
    for (int k = 0; k < kIcRowWidth; ++k) {
      const int u = k - kIcRowOffset;
      const bool inside = std::abs(u) <= d;
      ic_u_weights_[r][k] = static_cast<int16_t>(inside ? u : 0);
      ic_disc_[r][k] = static_cast<int16_t>(inside ? 1 : 0);
    }
  }
  for (int level = 0; level < options.levels; ++level)
    describers_.push_back(cv::ORB::create(options.features, static_cast<float>(options.scale_factor), 1, options.border,
                                          0, 2, cv::ORB::FAST_SCORE, 31, 20));
}

std::vector<int> OrbExtractor::levelBudgets(int n) const {
  const int levels = options_.levels;
  const double inv = 1.0 / options_.scale_factor;
  std::vector<int> budget(levels);
  double per_level = n * (1 - inv) / (1 - std::pow(inv, levels));
  int total = 0;
  for (int l = 0; l < levels - 1; ++l) {
    budget[l] = static_cast<int>(std::lround(per_level));
    total += budget[l];
    per_level *= inv;
  }
  budget[levels - 1] = std::max(n - total, 0);
  return budget;
}

std::vector<int> OrbExtractor::distributeQuadtree(const std::vector<cv::KeyPoint>& candidates, float x0, float y0,
                                                  float x1, float y1, int n) {
  std::vector<int> out;
  if (candidates.empty() || n <= 0) return out;
  // The nodes are a list (in `next` order) over one pool; each node's candidates are a contiguous range of
  // `order`, in candidate order, so a split partitions its range stably into its four quadrants.
  struct Node {
    float x0, y0, x1, y1;
    int begin, end;  // range in `order`
    int next;        // the next node in the list, -1 at its end
    int size() const { return end - begin; }
  };
  std::vector<Node> pool;
  std::vector<int> order, scratch;
  scratch.resize(candidates.size());

  // Initial nodes: roughly square, side by side along the longer axis; the empty ones dropped.
  const float w = x1 - x0, h = y1 - y0;
  const int n_init = std::max(1, static_cast<int>(std::lround(w / std::max(h, 1.0f))));
  const float step = w / n_init;
  std::vector<int> column_count(n_init, 0), column_of(candidates.size());
  for (size_t i = 0; i < candidates.size(); ++i) {
    column_of[i] = std::clamp(static_cast<int>((candidates[i].pt.x - x0) / step), 0, n_init - 1);
    ++column_count[column_of[i]];
  }
  std::vector<int> column_start(n_init + 1, 0);
  for (int c = 0; c < n_init; ++c) column_start[c + 1] = column_start[c] + column_count[c];
  order.resize(candidates.size());
  {
    std::vector<int> fill(column_start.begin(), column_start.end() - 1);
    for (size_t i = 0; i < candidates.size(); ++i) order[fill[column_of[i]]++] = static_cast<int>(i);
  }
  int head = -1, tail = -1, n_nodes = 0;
  for (int c = 0; c < n_init; ++c) {
    if (column_count[c] == 0) continue;
    pool.push_back({x0 + step * c, y0, x0 + step * (c + 1), y1, column_start[c], column_start[c + 1], -1});
    const int id = static_cast<int>(pool.size()) - 1;
    (tail < 0 ? head : pool[tail].next) = id;
    tail = id;
    ++n_nodes;
  }

  auto splittable = [](const Node& node) { return node.size() > 1 && node.x1 - node.x0 > 1.0f; };
  std::vector<int> to_split, prev_of;
  while (n_nodes < n) {
    // Nodes with the most keypoints are split first, so the last pass stops exactly at the budget.
    to_split.clear();
    for (int id = head; id >= 0; id = pool[id].next)
      if (splittable(pool[id])) to_split.push_back(id);
    if (to_split.empty()) break;
    std::stable_sort(to_split.begin(), to_split.end(), [&](int a, int b) { return pool[a].size() > pool[b].size(); });
    // Each node's predecessor, to put its children where it was.
    prev_of.assign(pool.size(), -1);
    for (int id = head, prev = -1; id >= 0; prev = id, id = pool[id].next) prev_of[id] = prev;
    for (const int id : to_split) {
      const Node node = pool[id];
      const float mx = 0.5f * (node.x0 + node.x1), my = 0.5f * (node.y0 + node.y1);
      const auto quadrant = [&](int i) {
        const cv::Point2f& p = candidates[i].pt;
        return (p.x < mx ? 0 : 1) + (p.y < my ? 0 : 2);
      };
      std::array<int, 5> start{};
      for (int k = node.begin; k < node.end; ++k) ++start[quadrant(order[k]) + 1];
      for (int q = 0; q < 4; ++q) start[q + 1] += start[q];
      std::array<int, 4> fill = {start[0], start[1], start[2], start[3]};
      for (int k = node.begin; k < node.end; ++k) scratch[fill[quadrant(order[k])]++] = order[k];
      std::copy(scratch.begin(), scratch.begin() + node.size(), order.begin() + node.begin);
      const std::array<std::array<float, 4>, 4> box = {{{node.x0, node.y0, mx, my},
                                                        {mx, node.y0, node.x1, my},
                                                        {node.x0, my, mx, node.y1},
                                                        {mx, my, node.x1, node.y1}}};
      // The non-empty children replace the node in the list, in quadrant order.
      int prev = prev_of[id];
      for (int q = 0; q < 4; ++q) {
        if (start[q + 1] == start[q]) continue;
        pool.push_back(
            {box[q][0], box[q][1], box[q][2], box[q][3], node.begin + start[q], node.begin + start[q + 1], -1});
        const int child = static_cast<int>(pool.size()) - 1;
        (prev < 0 ? head : pool[prev].next) = child;
        prev = child;
        ++n_nodes;
      }
      pool[prev].next = node.next;  // a node with two or more keypoints has a child
      if (node.next >= 0) {         // (the next node may be a child made in this pass)
        prev_of.resize(pool.size(), -1);
        prev_of[node.next] = prev;
      }
      --n_nodes;
      if (n_nodes >= n) break;
    }
  }
  out.reserve(n_nodes);
  for (int id = head; id >= 0; id = pool[id].next) {
    const Node& node = pool[id];
    int best = order[node.begin];
    for (int k = node.begin; k < node.end; ++k)
      if (candidates[order[k]].response > candidates[best].response) best = order[k];
    out.push_back(best);
  }
  if (static_cast<int>(out.size()) > n) {  // the last split may overshoot by up to 3
    std::stable_sort(out.begin(), out.end(),
                     [&](int a, int b) { return candidates[a].response > candidates[b].response; });
    out.resize(n);
  }
  std::sort(out.begin(), out.end());
  return out;
}

float OrbExtractor::icAngle(const cv::Mat& image, const cv::Point2f& pt) const {
  const int cx = cvRound(pt.x), cy = cvRound(pt.y);
  const int step = static_cast<int>(image.step1());
  // Each row of the disc is read as 32 pixels (u = -16..15) against its weights, zero outside the disc: a
  // fixed-length loop the compiler vectorises; the sums are the same integers as over the disc alone.
  const uint8_t* first = image.ptr<uint8_t>(cy - kHalfPatch) + cx - kIcRowOffset;
  int m10 = 0, m01 = 0;
  for (int r = 0; r < kIcRows; ++r) {
    const uint8_t* row = first + r * step;
    const int16_t* wu = ic_u_weights_[r].data();
    const int16_t* in = ic_disc_[r].data();
    int row_m10 = 0, row_sum = 0;
    for (int k = 0; k < kIcRowWidth; ++k) {
      row_m10 += wu[k] * row[k];
      row_sum += in[k] * row[k];
    }
    m10 += row_m10;
    m01 += (r - kHalfPatch) * row_sum;
  }
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

namespace {

// The FAST cells of one pyramid level: about cell_size px squares tiling the level inside its border.
struct LevelCells {
  LevelCells(int w_, int h_, int border_, int cell_size)
      : w(w_),
        h(h_),
        border(border_),
        nx(std::max(1, (w - 2 * border) / cell_size)),
        ny(std::max(1, (h - 2 * border) / cell_size)),
        cw(static_cast<float>(w - 2 * border) / nx),
        ch(static_cast<float>(h - 2 * border) / ny) {}
  int w, h, border, nx, ny;
  float cw, ch;
  int count() const { return nx * ny; }
  bool inside(const cv::Point2f& p) const {
    return p.x >= border && p.y >= border && p.x < w - border && p.y < h - border;
  }
  // Cell `index`'s level pixels.
  cv::Rect rect(int index) const {
    const int cx = index % nx, cy = index / nx;
    const int x0 = border + static_cast<int>(cx * cw), y0 = border + static_cast<int>(cy * ch);
    const int x1 = border + static_cast<int>((cx + 1) * cw), y1 = border + static_cast<int>((cy + 1) * ch);
    return cv::Rect(x0, y0, x1 - x0, y1 - y0);
  }
  int cellOf(const cv::Point2f& p) const {
    const int cx = std::min(static_cast<int>((p.x - border) / cw), nx - 1);
    const int cy = std::min(static_cast<int>((p.y - border) / ch), ny - 1);
    return cy * nx + cx;
  }
  // FAST at `threshold` on cell `index` and a 3 px margin (so the cell's own pixels are all tested), the
  // corners kept inside the cell and the border, level pixels.
  std::vector<cv::KeyPoint> search(const cv::Mat& level_image, int index, int threshold) const {
    const cv::Rect cell = rect(index);
    const int x0 = cell.x, y0 = cell.y, x1 = cell.x + cell.width, y1 = cell.y + cell.height;
    const cv::Rect roi(x0 - 3, y0 - 3, x1 - x0 + 6, y1 - y0 + 6);
    std::vector<cv::KeyPoint> raw, out;
    cv::FAST(level_image(roi), raw, threshold, true);
    for (cv::KeyPoint kp : raw) {
      kp.pt.x += roi.x;
      kp.pt.y += roi.y;
      if (kp.pt.x < x0 || kp.pt.y < y0 || kp.pt.x >= x1 || kp.pt.y >= y1 || !inside(kp.pt)) continue;
      out.push_back(kp);
    }
    return out;
  }
};

// Whether any level-0 pixel that a corner of the level cell `cell` would be labelled by is neither dynamic
// (1) nor a static object (>= 1000): if none is, every corner the cell could give is dropped.
bool cellHasUnlabelledPixel(const cv::Mat& labels, double s, const cv::Rect& cell) {
  const int u0 = std::min(static_cast<int>((cell.x + 0.5) * s), labels.cols - 1);
  const int u1 = std::min(static_cast<int>((cell.x + cell.width - 1 + 0.5) * s), labels.cols - 1);
  const int v0 = std::min(static_cast<int>((cell.y + 0.5) * s), labels.rows - 1);
  const int v1 = std::min(static_cast<int>((cell.y + cell.height - 1 + 0.5) * s), labels.rows - 1);
  for (int v = v0; v <= v1; ++v) {
    const uint16_t* row = labels.ptr<uint16_t>(v);
    for (int u = u0; u <= u1; ++u)
      if (row[u] != 1 && row[u] < 1000) return true;
  }
  return false;
}

// The level rect FAST searches for the level-0 pixel box `box`: 3 px before it (FAST's own border) and 5
// after, plus `pad` on every side.
cv::Rect levelSearchRect(const cv::Rect& box, double s, int pad) {
  return cv::Rect(static_cast<int>(box.x / s) - 3 - pad, static_cast<int>(box.y / s) - 3 - pad,
                  static_cast<int>(box.width / s) + 8 + 2 * pad, static_cast<int>(box.height / s) + 8 + 2 * pad);
}

}  // namespace

StaticRegions OrbExtractor::staticRegions(const cv::Mat& labels) {
  StaticRegions out;
  cv::Mat is_static;  // 255 where a label is >= 1000: memchr and memrchr find where a row has any
  cv::compare(labels, 999, is_static, cv::CMP_GT);
  std::vector<uint16_t> ids;
  std::vector<cv::Vec4i> extent;  // per id: x0, y0, x1, y1 (inclusive)
  for (int y = 0; y < labels.rows; ++y) {
    const uint8_t* flag = is_static.ptr<uint8_t>(y);
    const auto* first = static_cast<const uint8_t*>(std::memchr(flag, 255, static_cast<size_t>(labels.cols)));
    if (!first) continue;
    const auto* end = static_cast<const uint8_t*>(memrchr(flag, 255, static_cast<size_t>(labels.cols))) + 1;
    const uint16_t* row = labels.ptr<uint16_t>(y);
    size_t last = 0;
    for (int x = static_cast<int>(first - flag); x < static_cast<int>(end - flag); ++x) {
      if (!flag[x]) continue;
      if (ids.empty() || ids[last] != row[x]) {
        last = static_cast<size_t>(std::find(ids.begin(), ids.end(), row[x]) - ids.begin());
        if (last == ids.size()) {
          ids.push_back(row[x]);
          extent.emplace_back(x, y, x, y);
        }
      }
      cv::Vec4i& e = extent[last];
      e[0] = std::min(e[0], x);
      e[2] = std::max(e[2], x);
      e[3] = y;  // rows are visited in order
    }
  }
  for (const cv::Vec4i& e : extent) {
    const cv::Rect box(e[0], e[1], e[2] - e[0] + 1, e[3] - e[1] + 1);
    out.objects.push_back(box);
    out.all = out.all.empty() ? box : (out.all | box);
  }
  return out;
}

// Each object is searched in its own rect: its level box with 6 px more on every side (a corner's test and
// its non-maximum suppression read 4 px around it), clipped to the rect of all objects, whose edges the
// single search had too; overlapping rects are merged.
std::vector<cv::KeyPoint> OrbExtractor::staticObjectCorners(const cv::Mat& level_image, double s,
                                                            const StaticRegions& regions, int threshold) {
  const cv::Rect level_rect(0, 0, level_image.cols, level_image.rows);
  const cv::Rect all = levelSearchRect(regions.all, s, 0) & level_rect;
  std::vector<cv::Rect> rects;
  for (const cv::Rect& box : regions.objects) {
    cv::Rect r = levelSearchRect(box, s, 6) & all;
    if (r.empty()) continue;
    // Merge with every rect it overlaps, until it overlaps none.
    for (bool merged = true; merged;) {
      merged = false;
      for (size_t i = 0; i < rects.size(); ++i)
        if (!(rects[i] & r).empty()) {
          r |= rects[i];
          rects.erase(rects.begin() + static_cast<std::ptrdiff_t>(i));
          merged = true;
          break;
        }
    }
    rects.push_back(r);
  }
  std::vector<cv::KeyPoint> corners, raw;
  for (const cv::Rect& roi : rects) {
    if (roi.width <= 7 || roi.height <= 7) continue;
    raw.clear();
    cv::FAST(level_image(roi), raw, threshold, true);
    for (cv::KeyPoint kp : raw) {
      kp.pt.x += roi.x;
      kp.pt.y += roi.y;
      corners.push_back(kp);
    }
  }
  std::stable_sort(corners.begin(), corners.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
    return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x < b.pt.x;
  });
  return corners;
}

void OrbExtractor::detectLevel(const cv::Mat& level_image, int level, const cv::Mat& labels,
                               const StaticRegions& static_regions, int n_level, const PreparedLevel* prepared,
                               std::vector<cv::KeyPoint>& level_kps, std::vector<uint16_t>& level_labels) const {
  const bool has_labels = !labels.empty();
  const int border = options_.border;
  const int w = level_image.cols, h = level_image.rows;
  const double s = pyramid_.scale[level];
  // FAST at the initial threshold over the whole level; cells left without a corner are searched
  // again at the fallback threshold; static-object regions at their own (lower) threshold.
  const LevelCells cells(w, h, border, options_.cell_size);
  auto labelAt = [&](const cv::Point2f& p) -> uint16_t {
    if (!has_labels) return 0;
    const int x0 = std::min(static_cast<int>((p.x + 0.5) * s), labels.cols - 1);  // level-0 pixel
    const int y0 = std::min(static_cast<int>((p.y + 0.5) * s), labels.rows - 1);
    return labels.at<uint16_t>(y0, x0);
  };
  std::vector<cv::KeyPoint> background, objects;
  std::vector<uint16_t> bg_label, obj_label;
  std::vector<uint8_t> cell_found(cells.count(), 0);
  std::vector<cv::KeyPoint> raw;
  if (!prepared) cv::FAST(level_image, raw, options_.fast_initial, true);
  for (const cv::KeyPoint& kp : prepared ? prepared->corners : raw) {
    if (!cells.inside(kp.pt)) continue;
    const uint16_t label = labelAt(kp.pt);
    if (label == 1 || label >= 1000) continue;  // dynamic: dropped; static objects: searched below
    cell_found[cells.cellOf(kp.pt)] = 1;
    background.push_back(kp);
    bg_label.push_back(label);
  }
  for (int cell = 0; cell < cells.count(); ++cell) {
    if (cell_found[cell]) continue;
    // Searched ahead when the cell was empty without the mask too; else (the mask emptied it) here, unless
    // the mask covers all of it.
    const bool known = prepared && prepared->cell_searched[cell];
    if (!known && has_labels && !cellHasUnlabelledPixel(labels, s, cells.rect(cell))) continue;
    const std::vector<cv::KeyPoint> found =
        known ? std::vector<cv::KeyPoint>() : cells.search(level_image, cell, options_.fast_fallback);
    for (const cv::KeyPoint& kp : known ? prepared->cell_corners[cell] : found) {
      const uint16_t label = labelAt(kp.pt);
      if (label == 1 || label >= 1000) continue;
      background.push_back(kp);
      bg_label.push_back(label);
    }
  }
  if (!static_regions.all.empty()) {
    for (const cv::KeyPoint& kp : staticObjectCorners(level_image, s, static_regions, options_.static_object_fast)) {
      if (!cells.inside(kp.pt)) continue;
      const uint16_t label = labelAt(kp.pt);
      if (label < 1000) continue;
      objects.push_back(kp);
      obj_label.push_back(label);
    }
  }

  const int n_obj_wanted = std::max(static_cast<int>(std::lround(options_.static_object_budget_share * n_level)),
                                    n_level - static_cast<int>(background.size()));
  const int n_obj = std::min(static_cast<int>(objects.size()), std::max(0, n_obj_wanted));
  const int n_bg = n_level - n_obj;
  for (int i : distributeQuadtree(background, border, border, w - border, h - border, n_bg)) {
    level_kps.push_back(background[i]);
    level_labels.push_back(bg_label[i]);
  }
  for (int i : distributeQuadtree(objects, border, border, w - border, h - border, n_obj)) {
    level_kps.push_back(objects[i]);
    level_labels.push_back(obj_label[i]);
  }
  if (level_kps.empty()) return;

  for (cv::KeyPoint& kp : level_kps) {
    kp.angle = icAngle(level_image, kp.pt);
    kp.octave = 0;
    kp.size = 31.f;
  }
}

namespace {

cv::Mat greyOf(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("OrbExtractor: empty image");
  if (image.type() == CV_8UC1) return image;
  if (image.type() != CV_8UC3) throw std::invalid_argument("OrbExtractor: image must be CV_8UC1 or CV_8UC3");
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

}  // namespace

PreparedImage OrbExtractor::pyramids(const cv::Mat& grey) const {
  PreparedImage p;
  p.grey = grey;
  const int border = options_.border;
  // The pyramid (each level from the one before), up to the first level too small for features.
  for (int level = 0; level < options_.levels; ++level) {
    cv::Mat level_image = grey;
    if (level > 0) {
      const double s = pyramid_.scale[level];
      cv::Size size(static_cast<int>(std::lround(grey.cols / s)), static_cast<int>(std::lround(grey.rows / s)));
      cv::resize(p.level_images.back(), level_image, size, 0, 0, cv::INTER_LINEAR);
    }
    if (level_image.cols <= 2 * border + 8 || level_image.rows <= 2 * border + 8) break;
    p.level_images.push_back(level_image);
  }
  // rBRIEF is read where OpenCV's ORB always read it: on its own pyramid, each level resized from the one
  // before with INTER_LINEAR_EXACT (ours uses INTER_LINEAR; 2-3.5 of 256 bits would differ on levels 1-7).
  p.describe_images.resize(p.level_images.size());
  for (size_t level = 0; level < p.level_images.size(); ++level) {
    if (level == 0)
      p.describe_images[0] = grey;
    else
      cv::resize(p.describe_images[level - 1], p.describe_images[level], p.level_images[level].size(), 0, 0,
                 cv::INTER_LINEAR_EXACT);
  }
  return p;
}

std::shared_ptr<const PreparedImage> OrbExtractor::prepare(const cv::Mat& image) const {
  cv::Mat grey = greyOf(image);
  if (grey.data == image.data) grey = grey.clone();  // the caller's pixels are borrowed
  auto p = std::make_shared<PreparedImage>(pyramids(grey));
  p->levels.resize(p->level_images.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(p->level_images.size())), [&](const cv::Range& range) {
    for (int level = range.start; level < range.end; ++level) {
      const cv::Mat& image = p->level_images[level];
      PreparedLevel& out = p->levels[level];
      cv::FAST(image, out.corners, options_.fast_initial, true);
      const LevelCells cells(image.cols, image.rows, options_.border, options_.cell_size);
      std::vector<char> found(cells.count(), 0);
      for (const cv::KeyPoint& kp : out.corners)
        if (cells.inside(kp.pt)) found[cells.cellOf(kp.pt)] = 1;
      out.cell_searched.assign(cells.count(), 0);
      out.cell_corners.resize(cells.count());
      for (int cell = 0; cell < cells.count(); ++cell)
        if (!found[cell]) {
          out.cell_corners[cell] = cells.search(image, cell, options_.fast_fallback);
          out.cell_searched[cell] = 1;
        }
    }
  });
  return p;
}

std::shared_ptr<FeatureSet> OrbExtractor::extract(const cv::Mat& image, const cv::Mat& labels, int budget,
                                                  const PreparedImage* prepared) const {
  if (prepared && (image.empty() || prepared->grey.size() != image.size()))
    throw std::invalid_argument("OrbExtractor: the prepared image is not this image's size");
  const PreparedImage own = prepared ? PreparedImage{} : pyramids(greyOf(image));
  const PreparedImage& p = prepared ? *prepared : own;
  const cv::Mat& grey = p.grey;
  const std::vector<cv::Mat>& level_images = p.level_images;
  const std::vector<cv::Mat>& describe_images = p.describe_images;
  const bool has_labels = !labels.empty();
  if (has_labels && (labels.type() != CV_16UC1 || labels.size() != image.size()))
    throw std::invalid_argument("OrbExtractor: label mask must be CV_16UC1 of the image size");

  auto features = std::make_shared<FeatureSet>();
  features->width = image.cols;
  features->height = image.rows;
  const std::vector<int> budgets = levelBudgets(budget > 0 ? budget : options_.features);
  const StaticRegions static_regions = has_labels ? staticRegions(labels) : StaticRegions{};

  // Each level's keypoints and descriptors depend on that level alone: the levels are worked in parallel
  // (OpenCV's thread pool), each into its own slot, and gathered in level order, so the result is the same
  // as one level after the other, whatever the threads. rBRIEF: the level's own cv::ORB (one level) blurs
  // the level's describe image (7 x 7, sigma 2) and describes the level's keypoints there: the same bits
  // as one cv::ORB::compute over all levels, which builds that pyramid itself.
  const int n_levels = static_cast<int>(level_images.size());
  std::vector<std::vector<cv::KeyPoint>> found(n_levels);
  std::vector<std::vector<uint16_t>> found_labels(n_levels);
  std::vector<cv::Mat> found_descriptors(n_levels);
  std::vector<char> described_in_order(n_levels, 1);
  cv::parallel_for_(cv::Range(0, n_levels), [&](const cv::Range& range) {
    for (int level = range.start; level < range.end; ++level) {
      detectLevel(level_images[level], level, labels, static_regions, budgets[level],
                  p.levels.empty() ? nullptr : &p.levels[level], found[level], found_labels[level]);
      if (found[level].empty()) continue;
      std::vector<cv::KeyPoint> described = found[level];
      describers_[level]->compute(describe_images[level], described, found_descriptors[level]);
      bool same = described.size() == found[level].size();
      for (size_t i = 0; same && i < described.size(); ++i)  // OpenCV keeps the order and drops none inside the border
        same = std::fabs(described[i].pt.x - found[level][i].pt.x) <= 0.01f &&
               std::fabs(described[i].angle - found[level][i].angle) <= 0.01f;
      described_in_order[level] = same;
    }
  });
  std::vector<cv::Mat> descriptor_rows;
  for (int level = 0; level < n_levels; ++level) {
    if (!described_in_order[level])
      throw std::logic_error("OrbExtractor: cv::ORB::compute dropped or reordered keypoints");
    if (!found_descriptors[level].empty()) descriptor_rows.push_back(found_descriptors[level]);
    const double s = pyramid_.scale[level];
    const std::vector<cv::KeyPoint>& level_kps = found[level];
    const std::vector<uint16_t>& level_labels = found_labels[level];

    for (size_t i = 0; i < level_kps.size(); ++i) {
      cv::KeyPoint kp = level_kps[i];
      // Level pixel centres to level-0 pixels as cv::resize samples them: (x + 0.5) s - 0.5.
      kp.pt = (kp.pt + cv::Point2f(0.5f, 0.5f)) * static_cast<float>(s) - cv::Point2f(0.5f, 0.5f);
      kp.octave = level;
      kp.size = static_cast<float>(31.0 * s);
      features->keypoints.push_back(kp);
      features->labels.push_back(level_labels[i]);
      const int x0 = std::min(static_cast<int>(kp.pt.x + 0.5f), image.cols - 1);
      const int y0 = std::min(static_cast<int>(kp.pt.y + 0.5f), image.rows - 1);
      if (image.type() == CV_8UC3) {
        features->colours.push_back(image.at<cv::Vec3b>(y0, x0));
      } else {
        const uint8_t g = grey.at<uint8_t>(y0, x0);
        features->colours.push_back(cv::Vec3b(g, g, g));
      }
    }
  }
  if (descriptor_rows.empty())
    features->descriptors = cv::Mat(0, 32, CV_8U);
  else
    cv::vconcat(descriptor_rows, features->descriptors);
  features->buildGrid();
  return features;
}

}  // namespace beslam::orb
