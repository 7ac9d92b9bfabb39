// Contour refinement on synthetic shapes with a known outline.
#include "beslam/mask_common/contour.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "beslam/mask_common/score.hpp"

using namespace beslam::mask;

namespace {

// A car-like silhouette (body + narrower raised cabin + a sloped windscreen) on a textured background,
// inside a rectangular "projected box" region with background around it.
struct Shape {
  cv::Mat gray, truth, region;
};

Shape carShape(uint32_t seed, int contrast) {
  Shape s;
  const cv::Size size(220, 110);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.f, 2.f);
  cv::Mat img(size, CV_32F);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) img.at<float>(y, x) = 110.f + 8.f * std::sin(0.3f * x) * std::cos(0.2f * y);
  s.truth = cv::Mat::zeros(size, CV_8UC1);
  const std::vector<cv::Point> outline = {{12, 100}, {12, 58},  {60, 52},  {85, 14},
                                          {150, 14}, {178, 52}, {207, 58}, {207, 100}};
  cv::fillPoly(s.truth, std::vector<std::vector<cv::Point>>{outline}, cv::Scalar(255));
  img.setTo(cv::Scalar(110 + contrast), s.truth);
  cv::GaussianBlur(img, img, cv::Size(0, 0), 0.7);
  s.gray = cv::Mat(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      s.gray.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(img.at<float>(y, x) + noise(rng));
  s.region = cv::Mat::zeros(size, CV_8UC1);
  cv::rectangle(s.region, cv::Point(8, 10), cv::Point(211, 104), cv::Scalar(255), cv::FILLED);
  return s;
}

}  // namespace

TEST(Contour, RecoversAKnownOutline) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const Shape s = carShape(seed, 60);
    const ContourResult r = refineContour(s.gray, s.region, cv::Mat(), ContourParams{});
    ASSERT_TRUE(r.refined) << "seed " << seed;
    const double before = maskIou(s.region, s.truth), after = maskIou(r.mask, s.truth);
    EXPECT_GT(after, 0.9) << "seed " << seed;
    EXPECT_GT(after, before + 0.1) << "seed " << seed;
    for (bool e : r.from_edges) EXPECT_TRUE(e);
    EXPECT_LT(r.smoothness, 0.5);  // equation (3) at the solution: edges agree with the curves' normals
    // The six pieces meet at their shared ends (C0 joins).
    EXPECT_NEAR(r.curves[0](r.curves[0].x_mid + r.curves[0].half_width),
                r.curves[1](r.curves[1].x_mid - r.curves[1].half_width), 1.0);
    EXPECT_NEAR(r.curves[4](r.curves[4].x_mid - r.curves[4].half_width),
                r.curves[5](r.curves[5].x_mid + r.curves[5].half_width), 1.0);
  }
}

TEST(Contour, FallsBackToTheRegionWhereEdgesAreWeak) {
  // No contrast at all: nothing but the projected region.
  const Shape flat = carShape(4, 0);
  const ContourResult r = refineContour(flat.gray, flat.region, cv::Mat(), ContourParams{});
  EXPECT_FALSE(r.refined);
  EXPECT_EQ(cv::countNonZero(r.mask != flat.region), 0);
  // With a prior (e.g. LiDAR points) the fallback is the prior.
  cv::Mat prior = cv::Mat::zeros(flat.region.size(), CV_8UC1);
  cv::rectangle(prior, cv::Point(20, 30), cv::Point(200, 100), cv::Scalar(255), cv::FILLED);
  const ContourResult rp = refineContour(flat.gray, flat.region, prior, ContourParams{});
  EXPECT_EQ(cv::countNonZero(rp.mask != prior), 0);
}

TEST(Contour, PriorGuidesTheEdgeChoice) {
  const Shape s = carShape(5, 60);
  // A prior that is the truth dilated by 3 px (what LiDAR splats give): the result hugs the edges.
  cv::Mat prior;
  cv::dilate(s.truth, prior, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(7, 7)));
  cv::bitwise_and(prior, s.region, prior);
  const ContourResult r = refineContour(s.gray, s.region, prior, ContourParams{});
  ASSERT_TRUE(r.refined);
  EXPECT_GT(maskIou(r.mask, s.truth), maskIou(prior, s.truth));
  EXPECT_GT(maskIou(r.mask, s.truth), 0.93);
}

TEST(Contour, TinyCropsKeepTheRegion) {
  const cv::Mat gray(6, 8, CV_8UC1, cv::Scalar(50)), region(6, 8, CV_8UC1, cv::Scalar(255));
  const ContourResult r = refineContour(gray, region, cv::Mat(), ContourParams{});
  EXPECT_FALSE(r.refined);
  EXPECT_EQ(cv::countNonZero(r.mask), 48);
}
