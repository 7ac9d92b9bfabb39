// Box projection against hand-computed corners, near-plane clipping, labels and painting order.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "beslam/mask_common/box_projection.hpp"
#include "beslam/mask_common/mask_builder.hpp"
#include "beslam/sdk/detector.hpp"
#include "beslam/sdk/views.hpp"

using namespace beslam;
using namespace beslam::mask;

namespace {

Intrinsics camera() {
  Intrinsics K;
  K.fx = K.fy = 700, K.cx = 600, K.cy = 180, K.width = 1200, K.height = 360;
  return K;
}

beslam_box3d box(double x, double y, double z, double l, double w, double h, double yaw,
                 int motion = BESLAM_MOTION_DYNAMIC, int id = -1) {
  beslam_box3d b = sdk::newBox();
  b.center_cam[0] = x, b.center_cam[1] = y, b.center_cam[2] = z;
  b.size[0] = l, b.size[1] = w, b.size[2] = h;
  b.yaw = yaw;
  b.motion_state = motion;
  b.track_id = id;
  return b;
}

cv::Rect2f bounds(const std::vector<cv::Point2f>& p) {
  float u0 = 1e9f, v0 = 1e9f, u1 = -1e9f, v1 = -1e9f;
  for (const auto& q : p)
    u0 = std::min(u0, q.x), u1 = std::max(u1, q.x), v0 = std::min(v0, q.y), v1 = std::max(v1, q.y);
  return {u0, v0, u1 - u0, v1 - v0};
}

}  // namespace

TEST(Projection, CornersMatchHandComputation) {
  // Length 4 along camera x (yaw 0), width 2 along z, height 1.5, centre 10 m ahead on the axis.
  const beslam_box3d b = box(0, 0, 10, 4, 2, 1.5, 0);
  const Eigen::Matrix<double, 3, 8> c = sdk::boxCorners(b);
  // Corner 0: (+l/2, +h/2, +w/2) = (2, 0.75, 11).
  EXPECT_NEAR(c(0, 0), 2, 1e-12);
  EXPECT_NEAR(c(1, 0), 0.75, 1e-12);
  EXPECT_NEAR(c(2, 0), 11, 1e-12);
  // Hull: the near face (z = 9) encloses the far one: u = 600 +- 700*2/9, v = 180 +- 700*0.75/9.
  const std::vector<cv::Point2f> poly = projectBoxPolygon(b, camera(), 0.3, 0.0);
  ASSERT_EQ(poly.size(), 4u);
  const cv::Rect2f r = bounds(poly);
  EXPECT_NEAR(r.x, 600 - 1400.0 / 9, 1e-3);
  EXPECT_NEAR(r.x + r.width, 600 + 1400.0 / 9, 1e-3);
  EXPECT_NEAR(r.y, 180 - 525.0 / 9, 1e-3);
  EXPECT_NEAR(r.y + r.height, 180 + 525.0 / 9, 1e-3);
}

TEST(Projection, YawTurnsTheBoxAboutCameraY) {
  // yaw 90 degrees: the length axis points along -z (KITTI: x_box -> (cos, 0, -sin)).
  const beslam_box3d b = box(3, 1, 20, 4, 2, 1.5, M_PI / 2);
  const Eigen::Matrix<double, 3, 8> c = sdk::boxCorners(b);
  EXPECT_NEAR(c(0, 0), 3 + 1, 1e-9);   // +w/2 along x
  EXPECT_NEAR(c(2, 0), 20 - 2, 1e-9);  // +l/2 along -z
  // Rotated hull: extreme u from the nearest corners (z = 18, x = 2 and 4).
  const cv::Rect2f r = bounds(projectBoxPolygon(b, camera(), 0.3, 0.0));
  EXPECT_NEAR(r.x, 600 + 700 * 2.0 / 22, 1e-3);
  EXPECT_NEAR(r.x + r.width, 600 + 700 * 4.0 / 18, 1e-3);
  EXPECT_NEAR(r.y + r.height, 180 + 700 * 1.75 / 18, 1e-3);
}

TEST(Projection, MarginGrowsEverySide) {
  const beslam_box3d b = box(0, 0, 10, 4, 2, 1.5, 0);
  const cv::Rect2f r0 = bounds(projectBoxPolygon(b, camera(), 0.3, 0.0));
  const cv::Rect2f r5 = bounds(projectBoxPolygon(b, camera(), 0.3, 5.0));
  EXPECT_NEAR(r5.x, r0.x - 5, 0.6);
  EXPECT_NEAR(r5.y, r0.y - 5, 0.6);
  EXPECT_NEAR(r5.width, r0.width + 10, 1.2);
  EXPECT_NEAR(r5.height, r0.height + 10, 1.2);
}

TEST(Projection, ClipsAtTheNearPlane) {
  // Straddles the camera: 4 m long along z from -1.5 to 2.5.
  const beslam_box3d b = box(0.5, 0.5, 0.5, 4, 2, 1.5, M_PI / 2);
  const std::vector<Eigen::Vector3d> v = clippedBoxVertices(b, 0.3);
  ASSERT_EQ(v.size(), 8u);  // 4 corners in front, 4 edge crossings
  int on_plane = 0;
  for (const auto& p : v) {
    EXPECT_GE(p.z(), 0.3 - 1e-12);
    if (std::abs(p.z() - 0.3) < 1e-12) ++on_plane;
  }
  EXPECT_EQ(on_plane, 4);
  const std::vector<cv::Point2f> poly = projectBoxPolygon(b, camera(), 0.3, 2.0);
  ASSERT_GE(poly.size(), 3u);
  // The visible part fills much of the image (nearby) and stays within the guard band.
  for (const auto& p : poly) {
    EXPECT_GE(p.x, -16.0f - 1e-3f);
    EXPECT_LE(p.x, 1200 - 1 + 16.0f + 1e-3f);
  }
  EXPECT_EQ(cv::pointPolygonTest(poly, cv::Point2f(650, 250), false), 1.0);
}

TEST(Projection, BoxBehindTheCameraIsNotDrawn) {
  // Fully behind: a naive projection would fold it into the image.
  const beslam_box3d b = box(0, 0, -10, 4, 2, 1.5, 0.3);
  EXPECT_TRUE(clippedBoxVertices(b, 0.3).empty());
  EXPECT_TRUE(projectBoxPolygon(b, camera(), 0.3, 2.0).empty());
  // Beside the image: in front but outside the field of view.
  EXPECT_TRUE(projectBoxPolygon(box(60, 0, 5, 4, 2, 1.5, 0), camera(), 0.3, 2.0).empty());
  MaskBuilder builder(camera(), std::nullopt, MaskOptions{});
  cv::Mat mask = cv::Mat::zeros(360, 1200, CV_16UC1);
  builder.generate(cv::Mat(), beslam_point_cloud_view{}, {b}, mask);
  EXPECT_EQ(cv::countNonZero(mask), 0);
}

TEST(Labels, DynamicStaticAndUnknownPolicy) {
  EXPECT_EQ(labelFor(box(0, 0, 5, 1, 1, 1, 0, BESLAM_MOTION_DYNAMIC, 7), UnknownPolicy::Dynamic), BESLAM_LABEL_DYNAMIC);
  EXPECT_EQ(labelFor(box(0, 0, 5, 1, 1, 1, 0, BESLAM_MOTION_STATIC, 7), UnknownPolicy::Dynamic), 1007);
  EXPECT_EQ(labelFor(box(0, 0, 5, 1, 1, 1, 0, BESLAM_MOTION_STATIC, -1), UnknownPolicy::Dynamic), BESLAM_LABEL_DYNAMIC);
  EXPECT_EQ(labelFor(box(0, 0, 5, 1, 1, 1, 0, BESLAM_MOTION_UNKNOWN, 7), UnknownPolicy::Dynamic), BESLAM_LABEL_DYNAMIC);
  EXPECT_EQ(labelFor(box(0, 0, 5, 1, 1, 1, 0, BESLAM_MOTION_UNKNOWN, 7), UnknownPolicy::Static), 1007);
  EXPECT_EQ(labelFor(box(0, 0, 5, 1, 1, 1, 0, BESLAM_MOTION_UNKNOWN, 7), UnknownPolicy::Skip), std::nullopt);
  EXPECT_EQ(labelFor(box(0, 0, 5, 1, 1, 1, 0, BESLAM_MOTION_STATIC, 70000), UnknownPolicy::Dynamic),
            BESLAM_LABEL_DYNAMIC);
  EXPECT_THROW(parseUnknownPolicy("maybe"), std::invalid_argument);
}

TEST(Painting, NearerObjectsWinAndLabelsAreWritten) {
  const beslam_box3d far_static = box(0, 0, 20, 4, 2, 1.5, 0, BESLAM_MOTION_STATIC, 3);
  const beslam_box3d near_dynamic = box(0.5, 0, 10, 1, 1, 1.5, 0, BESLAM_MOTION_DYNAMIC, 4);
  MaskBuilder builder(camera(), std::nullopt, MaskOptions{});
  for (const auto& order :
       {std::vector<beslam_box3d>{far_static, near_dynamic}, std::vector<beslam_box3d>{near_dynamic, far_static}}) {
    cv::Mat mask = cv::Mat::zeros(360, 1200, CV_16UC1);
    builder.generate(cv::Mat(), beslam_point_cloud_view{}, order, mask);
    EXPECT_EQ(mask.at<uint16_t>(180, 635), BESLAM_LABEL_DYNAMIC);  // the near box's centre (u = 600 + 35)
    EXPECT_EQ(mask.at<uint16_t>(180, 560), 1003);                  // far box only
    EXPECT_EQ(mask.at<uint16_t>(20, 20), 0);
  }
}

TEST(Builder, RejectsInvalidCameraAndMissingExtrinsics) {
  Intrinsics bad = camera();
  bad.fx = 0;
  EXPECT_THROW(MaskBuilder(bad, std::nullopt, MaskOptions{}), std::invalid_argument);
  MaskOptions lidar;
  lidar.use_lidar = true;
  EXPECT_THROW(MaskBuilder(camera(), std::nullopt, lidar), std::invalid_argument);
  MaskBuilder ok(camera(), std::nullopt, MaskOptions{});
  beslam_box3d nan_box = box(0, 0, 10, 4, 2, 1.5, 0);
  nan_box.center_cam[2] = std::nan("");
  cv::Mat mask = cv::Mat::zeros(360, 1200, CV_16UC1);
  EXPECT_THROW(ok.generate(cv::Mat(), beslam_point_cloud_view{}, {nan_box}, mask), std::invalid_argument);
  // An image of another size than the camera's.
  const cv::Mat small(100, 200, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(ok.generate(small, beslam_point_cloud_view{}, {box(0, 0, 10, 4, 2, 1.5, 0)}, mask),
               std::invalid_argument);
}
