#include "box_match.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace beslam::detector_lidar::eval {

beslam_box3d labelToBox(const formats::ObjectLabel& label, int32_t class_id) {
  beslam_box3d box{};
  box.class_id = class_id;
  box.track_id = -1;
  box.center_cam[0] = label.p_cam_bottom.x();
  box.center_cam[1] = label.p_cam_bottom.y() - label.h / 2;
  box.center_cam[2] = label.p_cam_bottom.z();
  box.size[0] = label.l, box.size[1] = label.w, box.size[2] = label.h;
  box.yaw = label.ry;
  box.score = 1;
  return box;
}

double bevDistance(const beslam_box3d& a, const beslam_box3d& b) {
  return std::hypot(a.center_cam[0] - b.center_cam[0], a.center_cam[2] - b.center_cam[2]);
}

std::vector<Match> matchBev(const std::vector<beslam_box3d>& truth, const std::vector<beslam_box3d>& detections,
                            double max_distance) {
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  for (std::size_t t = 0; t < truth.size(); ++t)
    for (std::size_t d = 0; d < detections.size(); ++d) {
      const double e = bevDistance(truth[t], detections[d]);
      if (e <= max_distance) pairs.emplace_back(e, t, d);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<Match> matches(truth.size());
  std::vector<bool> used(detections.size(), false);
  for (std::size_t t = 0; t < truth.size(); ++t) matches[t].truth = t;
  for (const auto& [e, t, d] : pairs) {
    if (matches[t].detection >= 0 || used[d]) continue;
    matches[t].detection = static_cast<int>(d);
    matches[t].error = e;
    used[d] = true;
  }
  return matches;
}

}  // namespace beslam::detector_lidar::eval
