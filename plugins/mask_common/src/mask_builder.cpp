#include "beslam/mask_common/mask_builder.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace beslam::mask {

MaskBuilder::MaskBuilder(const Intrinsics& K, const std::optional<Eigen::Isometry3d>& T_cam_lidar,
                         const MaskOptions& options)
    : K_(K), T_cam_lidar_(T_cam_lidar), options_(options) {
  if (K.width <= 0 || K.height <= 0 || !(K.fx > 0) || !(K.fy > 0))
    throw std::invalid_argument("mask generator: camera intrinsics missing or invalid");
  if (options.use_lidar && !T_cam_lidar)
    throw std::invalid_argument("mask generator: LiDAR use needs the LiDAR-to-camera extrinsics (T_cam_lidar)");
}

std::vector<ObjectMask> MaskBuilder::objects(const cv::Mat& gray, const beslam_point_cloud_view& lidar,
                                             const std::vector<beslam_box3d>& boxes) const {
  std::vector<ObjectMask> out;
  if (!gray.empty() && (gray.cols != K_.width || gray.rows != K_.height || gray.type() != CV_8UC1))
    throw std::invalid_argument("mask generator: image is " + std::to_string(gray.cols) + "x" +
                                std::to_string(gray.rows) + " (or not 8-bit grey), the camera " +
                                std::to_string(K_.width) + "x" + std::to_string(K_.height));
  CameraPoints points;
  const bool have_lidar = options_.use_lidar && lidar.data != nullptr && lidar.count > 0;
  if (have_lidar)
    points = lidarToCamera(lidar.data, lidar.count, lidar.stride_bytes >= 16 ? lidar.stride_bytes / 4 : 4,
                           *T_cam_lidar_, K_, 0.5, options_.max_range);
  const cv::Rect image(0, 0, K_.width, K_.height);
  struct ContourWork {
    size_t object;          // in out
    cv::Mat region, prior;  // refineContour's inputs
  };
  std::vector<ContourWork> refine;  // objects whose mask the edge contour refines
  for (const beslam_box3d& input : boxes) {
    for (double v : input.center_cam)
      if (!std::isfinite(v)) throw std::invalid_argument("box with a non-finite centre");
    for (double v : input.size)
      if (!std::isfinite(v) || v <= 0) throw std::invalid_argument("box with a non-finite or non-positive size");
    if (!std::isfinite(input.yaw)) throw std::invalid_argument("box with a non-finite yaw");
    const std::optional<uint16_t> label = labelFor(input, options_.unknown);
    if (!label) continue;
    ObjectMask obj;
    obj.input = input;
    obj.box = input;
    obj.label = *label;
    if (have_lidar && options_.refine_boxes) {
      BevRefineParams bev = options_.bev;
      bev.intrinsics = K_;
      const BevRefineResult r = refineBoxBev(input, points, bev);
      obj.box = r.box;
      obj.refined = r.refined;
      obj.lidar_points = r.points;
    }
    const std::vector<cv::Point2f> poly = projectBoxPolygon(obj.box, K_, options_.near, options_.margin_px);
    if (poly.size() < 3) {
      out.push_back(std::move(obj));
      continue;
    }
    const cv::Rect roi = cv::boundingRect(poly) & image;
    if (roi.area() <= 0) {
      out.push_back(std::move(obj));
      continue;
    }
    obj.roi = roi;
    cv::Mat region = cv::Mat::zeros(roi.size(), CV_8UC1);
    std::vector<cv::Point> ipoly;
    ipoly.reserve(poly.size());
    // Fixed point (4 fractional bits) keeps sub-pixel vertices.
    for (const cv::Point2f& p : poly)
      ipoly.emplace_back(static_cast<int>(std::lround((p.x - roi.x) * 16)),
                         static_cast<int>(std::lround((p.y - roi.y) * 16)));
    cv::fillConvexPoly(region, ipoly, cv::Scalar(255), cv::LINE_8, 4);
    cv::Mat prior;
    if (have_lidar && options_.point_masks) {
      // The object's own points: inside the (refined) box, above the ground.
      const std::vector<int> idx = pointsNearBox(obj.box, points, 0.15, options_.points.ground_clearance, &K_);
      prior = pointMask(points, idx, roi, region, options_.points);
      obj.from_points = !prior.empty();
      if (obj.lidar_points == 0) obj.lidar_points = static_cast<int>(idx.size());
    }
    obj.mask = prior.empty() ? region : prior;
    if (options_.contour && !gray.empty()) refine.push_back({out.size(), region, prior});
    out.push_back(std::move(obj));
  }
  // Edge contours, one box each, in parallel (OpenCV's pool): each writes its own object only.
  cv::parallel_for_(cv::Range(0, static_cast<int>(refine.size())), [&](const cv::Range& r) {
    for (int i = r.start; i < r.end; ++i) {
      ObjectMask& obj = out[refine[i].object];
      const ContourResult c = refineContour(gray(obj.roi), refine[i].region, refine[i].prior, options_.contour_params);
      obj.mask = c.mask;
      obj.from_contour = c.refined;
    }
  });
  return out;
}

void MaskBuilder::paint(const std::vector<ObjectMask>& objects, cv::Mat& mask) const {
  if (mask.type() != CV_16UC1) throw std::invalid_argument("mask generator: the mask buffer must be 16-bit labels");
  std::vector<size_t> order(objects.size());
  std::iota(order.begin(), order.end(), 0);
  auto depth = [&objects](size_t i) {
    const auto& c = objects[i].box.center_cam;
    return c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
  };
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return depth(a) > depth(b); });
  const cv::Rect bounds(0, 0, mask.cols, mask.rows);
  for (size_t i : order) {
    const ObjectMask& o = objects[i];
    if (o.mask.empty() || o.roi.area() <= 0) continue;
    const cv::Rect r = o.roi & bounds;
    if (r.area() <= 0) continue;
    mask(r).setTo(cv::Scalar(o.label), o.mask(cv::Rect(r.x - o.roi.x, r.y - o.roi.y, r.width, r.height)));
  }
}

}  // namespace beslam::mask
