#include <algorithm>
#include <cmath>

#include "features/feature_set.hpp"

namespace beslam::orb {

FeatureGrid::FeatureGrid(const std::vector<cv::KeyPoint>& keypoints, int width, int height)
    : inv_cell_w_(static_cast<float>(kCols) / static_cast<float>(std::max(width, 1))),
      inv_cell_h_(static_cast<float>(kRows) / static_cast<float>(std::max(height, 1))) {
  const int n_cells = kCols * kRows;
  std::vector<int> cell_of(keypoints.size());
  std::vector<int> count(n_cells + 1, 0);
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const int cx = std::clamp(static_cast<int>(keypoints[i].pt.x * inv_cell_w_), 0, kCols - 1);
    const int cy = std::clamp(static_cast<int>(keypoints[i].pt.y * inv_cell_h_), 0, kRows - 1);
    cell_of[i] = cy * kCols + cx;
    ++count[cell_of[i] + 1];
  }
  start_.assign(n_cells + 1, 0);
  for (int c = 0; c < n_cells; ++c) start_[c + 1] = start_[c] + count[c + 1];
  index_.resize(keypoints.size());
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < keypoints.size(); ++i) index_[fill[cell_of[i]]++] = static_cast<int>(i);
}

std::vector<int> FeatureGrid::query(const std::vector<cv::KeyPoint>& keypoints, float u, float v, float r,
                                    int min_level, int max_level) const {
  // The cells' keypoints filtered as they are visited, row by row, without gathering them first: a query
  // is made per projected map point, thousands per frame.
  std::vector<int> out;
  int c0 = 0, c1 = -1, r0 = 0, r1 = -1;
  if (!cellRange(u - r, v - r, u + r, v + r, c0, c1, r0, r1)) return out;
  for (int row = r0; row <= r1; ++row)
    for (int cell = row * kCols + c0, last = row * kCols + c1; cell <= last; ++cell)
      for (int k = start_[cell]; k < start_[cell + 1]; ++k) {
        const int i = index_[k];
        const cv::KeyPoint& kp = keypoints[i];
        if (min_level >= 0 && kp.octave < min_level) continue;
        if (max_level >= 0 && kp.octave > max_level) continue;
        if (std::fabs(kp.pt.x - u) > r || std::fabs(kp.pt.y - v) > r) continue;
        out.push_back(i);
      }
  return out;
}

}  // namespace beslam::orb
