#include "sample_frames.hpp"

#include <gtest/gtest.h>

namespace beslam::pipeline::detail {
namespace {

TEST(SamplePositions, SpreadEvenlyAndNeverPastTheEnd) {
  EXPECT_EQ(samplePositions(100, 4), (std::set<size_t>{12, 37, 62, 87}));
  EXPECT_EQ(samplePositions(3, 6), (std::set<size_t>{0, 1, 2}));
  EXPECT_TRUE(samplePositions(100, 0).empty());
  EXPECT_TRUE(samplePositions(0, 5).empty());
}

TEST(SampleFrame, ColoursMasksAndFeaturesByRegion) {
  const cv::Mat grey(100, 200, CV_8UC1, cv::Scalar(128));
  cv::Mat labels = cv::Mat::zeros(100, 200, CV_16UC1);
  labels(cv::Rect(20, 40, 30, 30)).setTo(BESLAM_LABEL_DYNAMIC);
  labels(cv::Rect(120, 40, 30, 30)).setTo(BESLAM_LABEL_STATIC_BASE + 7);
  std::vector<beslam_keypoint> keypoints = {{135, 55, BESLAM_LABEL_STATIC_BASE + 7, BESLAM_KEYPOINT_MATCHED, 0},
                                            {90, 80, BESLAM_LABEL_BACKGROUND, 0, 0}};
  beslam_camera camera{};
  camera.width = 200;
  camera.height = 100;
  const cv::Mat drawn = drawSampleFrame(grey, labels, keypoints, {}, camera);
  ASSERT_EQ(drawn.type(), CV_8UC3);
  const cv::Vec3b moving = drawn.at<cv::Vec3b>(65, 25), parked_pixel = drawn.at<cv::Vec3b>(65, 125);
  EXPECT_GT(moving[2], moving[1] + 40) << "dynamic pixels tinted red";
  EXPECT_GT(parked_pixel[1], parked_pixel[2] + 40) << "static-object pixels tinted green";
  const cv::Vec3b parked_feature = drawn.at<cv::Vec3b>(55, 135), background_feature = drawn.at<cv::Vec3b>(80, 90);
  EXPECT_GT(parked_feature[1], 150);
  EXPECT_LT(parked_feature[2], 120);
  EXPECT_GT(background_feature[1], 150) << "yellow: green and red high, blue low";
  EXPECT_GT(background_feature[2], 150);
  EXPECT_LT(background_feature[0], 80);
  EXPECT_EQ(drawn.at<cv::Vec3b>(90, 190), cv::Vec3b(128, 128, 128)) << "unlabelled pixels untouched";
}

}  // namespace
}  // namespace beslam::pipeline::detail
