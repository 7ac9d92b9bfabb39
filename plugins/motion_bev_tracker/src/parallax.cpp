#include "beslam/motion/parallax.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <stdexcept>

namespace beslam::motion {

namespace {

// The box's 2D rectangle, clipped to the image; empty when it is too small to follow.
cv::Rect boxRect(const beslam_box3d& b, const cv::Size& image, int min_px, double inset) {
  const double w = b.bbox2d[2] - b.bbox2d[0], h = b.bbox2d[3] - b.bbox2d[1];
  if (!(w >= min_px) || !(h >= min_px)) return {};
  const cv::Rect r(cv::Point(static_cast<int>(std::lround(b.bbox2d[0] + inset * w)),
                             static_cast<int>(std::lround(b.bbox2d[1] + inset * h))),
                   cv::Point(static_cast<int>(std::lround(b.bbox2d[2] - inset * w)),
                             static_cast<int>(std::lround(b.bbox2d[3] - inset * h))));
  return r & cv::Rect(0, 0, image.width, image.height);
}

bool inside(const cv::Point2f& p, const beslam_box3d& b) {
  return p.x >= b.bbox2d[0] && p.x <= b.bbox2d[2] && p.y >= b.bbox2d[1] && p.y <= b.bbox2d[3];
}

bool followed(const beslam_box3d& b) {
  return b.track_id >= 0 && (b.flags & BESLAM_BOX_HAS_BBOX2D) != 0 && (b.flags & BESLAM_BOX_UNCERTAIN) == 0;
}

}  // namespace

std::string ParallaxParams::validate() const {
  if (!(min_baseline > 0)) return "parallax_min_baseline must be > 0";
  if (max_frames < 2) return "parallax_max_frames must be >= 2";
  if (!(min_ray_angle_deg >= 0 && min_ray_angle_deg < 90)) return "parallax_min_ray_angle must be in [0, 90)";
  if (corners < min_points) return "parallax_corners must be >= parallax_min_points";
  if (!(box_inset >= 0 && box_inset < 0.5)) return "parallax_box_inset must be in [0, 0.5)";
  if (!(max_flow_error > 0) || !(max_reprojection_px > 0)) return "parallax pixel tolerances must be > 0";
  if (!(depth_quantile >= 0 && depth_quantile <= 1)) return "parallax_depth_quantile must be in [0, 1]";
  if (min_points < 2) return "parallax_min_points must be >= 2";
  if (min_box_px < 4) return "parallax_min_box_px must be >= 4";
  return {};
}

double nearestCornerDepth(const beslam_box3d& b) {
  const double c = std::cos(b.yaw), s = std::sin(b.yaw);
  double nearest = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 4; ++i) {
    const double a = (i & 1 ? 0.5 : -0.5) * b.size[0], w = (i & 2 ? 0.5 : -0.5) * b.size[1];
    // Length along the heading (cos yaw, 0, -sin yaw), width across it (sin yaw, 0, cos yaw); height does not
    // change a corner's depth.
    nearest = std::min(nearest, b.center_cam[2] - a * s + w * c);
  }
  return nearest;
}

ParallaxCheck::ParallaxCheck(const ParallaxParams& params, double fx, double fy, double cx, double cy)
    : params_(params), fx_(fx), fy_(fy), cx_(cx), cy_(cy) {
  const std::string problem = params.validate();
  if (!problem.empty()) throw std::invalid_argument("motion tracker: " + problem);
  if (!(fx > 0) || !(fy > 0) || !std::isfinite(cx) || !std::isfinite(cy))
    throw std::invalid_argument("motion tracker: parallax needs the camera's focal length and principal point");
}

void ParallaxCheck::reset() {
  pyramids_.clear();
  sets_.clear();
}

void ParallaxCheck::seed(PointSet& set, const cv::Mat& gray, const Eigen::Isometry3d& T_world_cam,
                         const beslam_box3d& box) const {
  set = PointSet{T_world_cam, {}, {}, 0, frame_};
  const cv::Rect r = boxRect(box, gray.size(), params_.min_box_px, params_.box_inset);
  if (r.width < 4 || r.height < 4) return;
  // On the box's own pixels: the corner response of the whole image would cost a full-frame pass per box.
  cv::goodFeaturesToTrack(gray(r), set.first, params_.corners, 0.01, 4);
  for (cv::Point2f& p : set.first) p += cv::Point2f(static_cast<float>(r.x), static_cast<float>(r.y));
  set.latest = set.first;
}

std::optional<ParallaxMeasurement> ParallaxCheck::measure(const PointSet& set, const Eigen::Isometry3d& T_world_cam,
                                                          const beslam_box3d& box) const {
  const Eigen::Vector3d c0 = set.T_world_cam0.translation(), c1 = T_world_cam.translation();
  if ((c1 - c0).norm() < params_.min_baseline) return std::nullopt;
  const Eigen::Matrix3d R0 = set.T_world_cam0.linear(), R1 = T_world_cam.linear();
  auto reprojection = [&](const Eigen::Vector3d& p_cam, const cv::Point2f& px) {
    return std::hypot(fx_ * p_cam.x() / p_cam.z() + cx_ - px.x, fy_ * p_cam.y() / p_cam.z() + cy_ - px.y);
  };
  const double min_angle_rad = params_.min_ray_angle_deg * M_PI / 180;
  std::vector<double> depths;
  for (size_t i = 0; i < set.first.size(); ++i) {
    const Eigen::Vector3d d0 =
        R0 * Eigen::Vector3d((set.first[i].x - cx_) / fx_, (set.first[i].y - cy_) / fy_, 1.0).normalized();
    const Eigen::Vector3d d1 =
        R1 * Eigen::Vector3d((set.latest[i].x - cx_) / fx_, (set.latest[i].y - cy_) / fy_, 1.0).normalized();
    // Midpoint of the two rays: c0 + a d0 and c1 + b d1 closest to each other.
    const Eigen::Vector3d w = c0 - c1;
    const double A = d0.dot(d1), D = d0.dot(w), E = d1.dot(w), denom = 1 - A * A;
    if (denom < 1e-9) continue;  // parallel rays: no depth
    const double a = (A * E - D) / denom, b = (E - A * D) / denom;
    if (a <= 0 || b <= 0) continue;
    // Too little parallax gives no depth worth the name (a car far ahead, or near the direction of travel).
    if (std::acos(std::clamp(A, -1.0, 1.0)) < min_angle_rad) continue;
    const Eigen::Vector3d p_world = 0.5 * (c0 + a * d0 + c1 + b * d1);
    const Eigen::Vector3d p_cam0 = R0.transpose() * (p_world - c0), p_cam1 = R1.transpose() * (p_world - c1);
    if (p_cam0.z() <= 0.5 || p_cam1.z() <= 0.5) continue;
    if (reprojection(p_cam0, set.first[i]) > params_.max_reprojection_px ||
        reprojection(p_cam1, set.latest[i]) > params_.max_reprojection_px)
      continue;
    depths.push_back(p_cam1.z());
  }
  if (static_cast<int>(depths.size()) < params_.min_points) return std::nullopt;
  const double near = nearestCornerDepth(box);
  if (!(near > 0.5)) return std::nullopt;
  const size_t k = std::min(depths.size() - 1, static_cast<size_t>(params_.depth_quantile * (depths.size() - 1) + 0.5));
  std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(k), depths.end());
  return ParallaxMeasurement{box.track_id, depths[k] / near, static_cast<int>(depths.size())};
}

std::vector<ParallaxMeasurement> ParallaxCheck::update(const cv::Mat& gray,
                                                       const std::optional<Eigen::Isometry3d>& T_world_cam,
                                                       const std::vector<beslam_box3d>& boxes) {
  std::vector<ParallaxMeasurement> out;
  if (gray.empty() || !T_world_cam) {
    reset();
    return out;
  }
  if (gray.type() != CV_8UC1) throw std::invalid_argument("motion tracker: parallax needs an 8-bit grey image");
  const cv::Size window(21, 21);
  const int levels = 3;
  ++frame_;
  std::vector<cv::Mat> pyramid;
  cv::buildOpticalFlowPyramid(gray, pyramid, window, levels);
  // The pyramid a set's corners were last seen in (a track the detector missed for a frame or two keeps them).
  auto source = [&](const PointSet& set) -> const std::vector<cv::Mat>* {
    for (const auto& [frame, p] : pyramids_)
      if (frame == set.latest_frame && p[0].size() == gray.size()) return &p;
    return nullptr;
  };
  std::map<int32_t, PointSet> next;
  std::vector<int32_t> seen;
  for (const beslam_box3d& box : boxes) {
    if (!followed(box) || std::find(seen.begin(), seen.end(), box.track_id) != seen.end()) continue;
    seen.push_back(box.track_id);
    const auto it = sets_.find(box.track_id);
    const std::vector<cv::Mat>* from_pyramid = it != sets_.end() ? source(it->second) : nullptr;
    PointSet kept;
    if (!from_pyramid || it->second.latest.empty()) {
      seed(kept, gray, *T_world_cam, box);
      next.emplace(box.track_id, std::move(kept));
      continue;
    }
    const PointSet& set = it->second;
    std::vector<cv::Point2f> forward, backward;
    std::vector<unsigned char> ok_f, ok_b;
    std::vector<float> err;
    cv::calcOpticalFlowPyrLK(*from_pyramid, pyramid, set.latest, forward, ok_f, err, window, levels);
    cv::calcOpticalFlowPyrLK(pyramid, *from_pyramid, forward, backward, ok_b, err, window, levels);
    kept = PointSet{set.T_world_cam0, {}, {}, set.frames + 1, frame_};
    for (size_t i = 0; i < forward.size(); ++i) {
      if (!ok_f[i] || !ok_b[i]) continue;
      if (std::hypot(backward[i].x - set.latest[i].x, backward[i].y - set.latest[i].y) > params_.max_flow_error)
        continue;
      if (!inside(forward[i], box)) continue;
      kept.first.push_back(set.first[i]);
      kept.latest.push_back(forward[i]);
    }
    // Measured every frame once the baseline allows, on the same corners (a longer baseline, a better depth),
    // until they are too old or too few.
    if (const auto m = measure(kept, *T_world_cam, box)) out.push_back(*m);
    if (kept.frames >= params_.max_frames || static_cast<int>(kept.first.size()) < params_.min_points)
      seed(kept, gray, *T_world_cam, box);
    next.emplace(box.track_id, std::move(kept));
  }
  // Tracks not in this frame keep their corners while the pyramid they were last seen in is kept.
  for (auto& [id, set] : sets_)
    if (!next.count(id) && frame_ - set.latest_frame < kKeptPyramids) next.emplace(id, std::move(set));
  sets_ = std::move(next);
  pyramids_.emplace_back(frame_, std::move(pyramid));
  while (static_cast<int>(pyramids_.size()) > kKeptPyramids) pyramids_.pop_front();
  return out;
}

}  // namespace beslam::motion
