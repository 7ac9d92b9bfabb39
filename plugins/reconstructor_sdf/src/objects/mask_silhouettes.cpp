#include "objects/mask_silhouettes.hpp"

#include <algorithm>
#include <cmath>

namespace beslam::recon {

std::map<int32_t, SilhouetteSample> sampleSilhouettes(const cv::Mat& mask, const beslam_camera& camera,
                                                      const std::vector<beslam_box3d>& boxes, int grid) {
  std::map<int32_t, SilhouetteSample> out;
  if (grid < 2 || mask.empty() || mask.type() != CV_16UC1 || mask.cols != camera.width || mask.rows != camera.height ||
      !(camera.fx > 0 && camera.fy > 0))
    return out;
  // The bounding rectangle of each wanted label (one pass over the mask).
  std::map<uint16_t, cv::Rect> rects;
  for (const beslam_box3d& box : boxes)
    if (box.track_id >= 0 && box.track_id <= 0xffff - BESLAM_LABEL_STATIC_BASE)
      rects.emplace(static_cast<uint16_t>(BESLAM_LABEL_STATIC_BASE + box.track_id), cv::Rect());
  if (rects.empty()) return out;
  for (int y = 0; y < mask.rows; ++y) {
    const uint16_t* row = mask.ptr<uint16_t>(y);
    for (int x = 0; x < mask.cols; ++x) {
      if (row[x] < BESLAM_LABEL_STATIC_BASE) continue;
      const auto it = rects.find(row[x]);
      if (it == rects.end()) continue;
      it->second = it->second.empty() ? cv::Rect(x, y, 1, 1) : (it->second | cv::Rect(x, y, 1, 1));
    }
  }
  const cv::Rect image(0, 0, mask.cols, mask.rows);
  for (const auto& [label, rect] : rects) {
    if (rect.empty()) continue;
    const int gx = (rect.width + 3) / 4, gy = (rect.height + 3) / 4;
    const cv::Rect grown = cv::Rect(rect.x - gx, rect.y - gy, rect.width + 2 * gx, rect.height + 2 * gy) & image;
    SilhouetteSample sample;
    int inside = 0;
    for (int j = 0; j < grid; ++j)
      for (int i = 0; i < grid; ++i) {
        const double px = grown.x + (i + 0.5) * grown.width / grid, py = grown.y + (j + 0.5) * grown.height / grid;
        const int x = std::clamp(static_cast<int>(px), 0, mask.cols - 1),
                  y = std::clamp(static_cast<int>(py), 0, mask.rows - 1);
        const uint16_t l = mask.at<uint16_t>(y, x);
        if (l != label && l != BESLAM_LABEL_BACKGROUND) continue;
        sample.u_cam.push_back(
            Eigen::Vector3d((x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy, 1.0).normalized());
        sample.inside.push_back(l == label ? 1 : 0);
        inside += l == label;
      }
    if (inside > 0) out.emplace(static_cast<int32_t>(label - BESLAM_LABEL_STATIC_BASE), std::move(sample));
  }
  return out;
}

}  // namespace beslam::recon
