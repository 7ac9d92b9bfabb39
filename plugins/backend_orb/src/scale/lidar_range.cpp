#include "scale/lidar_range.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "features/feature_set.hpp"

namespace beslam::orb {

void setLidarRanges(FeatureSet& features, const Eigen::Matrix3Xf& p_cam, const Camera& camera,
                    const LidarRangeOptions& options) {
  features.lidar_range.assign(features.size(), 0.0f);
  if (p_cam.cols() == 0 || camera.width <= 0 || camera.height <= 0) return;
  // Nearest return per pixel (a z-buffer): where two returns meet in a pixel the camera sees the nearer.
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> depth(static_cast<size_t>(camera.width) * static_cast<size_t>(camera.height), inf);
  for (Eigen::Index j = 0; j < p_cam.cols(); ++j) {
    const float z = p_cam(2, j);
    if (!(z >= options.min_depth) || !std::isfinite(p_cam(0, j)) || !std::isfinite(p_cam(1, j))) continue;
    const long u = std::lround(camera.fx * p_cam(0, j) / z + camera.cx);
    const long v = std::lround(camera.fy * p_cam(1, j) / z + camera.cy);
    if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) continue;
    float& d = depth[static_cast<size_t>(v) * static_cast<size_t>(camera.width) + static_cast<size_t>(u)];
    d = std::min(d, z);
  }
  for (size_t i = 0; i < features.size(); ++i) {
    const cv::Point2f& pt = features.keypoints[i].pt;
    const long u0 = std::lround(pt.x), v0 = std::lround(pt.y);
    // The return nearest the keypoint in the image: on a surface seen at a slant the window's depths
    // spread around the keypoint's, and its nearest or mean return would bias the range.
    float nearest = inf, farthest = 0, closest = 0;
    double closest_d2 = std::numeric_limits<double>::infinity();
    for (long v = std::max(0L, v0 - options.half_height);
         v <= std::min<long>(camera.height - 1, v0 + options.half_height); ++v)
      for (long u = std::max(0L, u0 - options.half_width);
           u <= std::min<long>(camera.width - 1, u0 + options.half_width); ++u) {
        const float d = depth[static_cast<size_t>(v) * static_cast<size_t>(camera.width) + static_cast<size_t>(u)];
        if (d == inf) continue;
        nearest = std::min(nearest, d);
        farthest = std::max(farthest, d);
        const double d2 = (u - pt.x) * (u - pt.x) + (v - pt.y) * (v - pt.y);
        if (d2 < closest_d2) {
          closest_d2 = d2;
          closest = d;
        }
      }
    if (nearest == inf || farthest - nearest > options.max_depth_spread * nearest) continue;
    // The depth of the surface along the optical axis, as a distance along the keypoint's own ray.
    const double x = (pt.x - camera.cx) / camera.fx, y = (pt.y - camera.cy) / camera.fy;
    features.lidar_range[i] = static_cast<float>(closest * std::sqrt(1.0 + x * x + y * y));
  }
}

}  // namespace beslam::orb
