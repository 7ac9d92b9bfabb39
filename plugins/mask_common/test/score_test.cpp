// Scoring written masks against instance masks in the synthetic sequence layout.
#include "beslam/mask_common/score.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace fs = std::filesystem;
using namespace beslam::mask;

TEST(Score, ObjectIouUsesStaticIdsAndDynamicComponents) {
  cv::Mat inst = cv::Mat::zeros(50, 100, CV_16UC1), pred = cv::Mat::zeros(50, 100, CV_16UC1);
  inst(cv::Rect(10, 10, 20, 20)).setTo(3);     // parked car 3
  inst(cv::Rect(60, 10, 20, 20)).setTo(4);     // moving car 4
  pred(cv::Rect(10, 10, 20, 10)).setTo(1003);  // half of car 3
  pred(cv::Rect(60, 10, 20, 20)).setTo(1);     // all of car 4 ...
  pred(cv::Rect(90, 40, 5, 5)).setTo(1);       // ... and an unrelated dynamic blob (not counted)
  int label = 0;
  EXPECT_NEAR(objectIou(pred, inst, 3, &label), 0.5, 1e-9);
  EXPECT_EQ(label, 1003);
  EXPECT_NEAR(objectIou(pred, inst, 4, &label), 1.0, 1e-9);
  EXPECT_EQ(label, 1);
  EXPECT_EQ(objectIou(pred, inst, 9, &label), 0.0);
}

TEST(Score, SequenceLayoutFiltersAndLabels) {
  const fs::path d = fs::temp_directory_path() / ("beslam_score_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d / "seq" / "instance");
  fs::create_directories(d / "seq" / "label_02");
  fs::create_directories(d / "run" / "masks");
  cv::Mat inst = cv::Mat::zeros(60, 120, CV_16UC1), pred = cv::Mat::zeros(60, 120, CV_16UC1);
  inst(cv::Rect(10, 10, 20, 20)).setTo(1);
  inst(cv::Rect(60, 10, 20, 20)).setTo(2);
  inst(cv::Rect(90, 30, 20, 20)).setTo(3);
  pred(cv::Rect(10, 10, 20, 20)).setTo(1001);  // parked, right
  pred(cv::Rect(60, 10, 20, 20)).setTo(1002);  // moving but labelled static: wrong label, IoU 1
  cv::imwrite((d / "seq" / "instance" / "000000.png").string(), inst);
  cv::imwrite((d / "run" / "masks" / "000000.png").string(), pred);
  std::ofstream(d / "seq" / "label_02" / "00.txt")
      << "0 1 Car 0 0 0 10 10 30 30 1.5 1.8 4 1 1.6 10 0\n"
      << "0 2 Car 0 0 0 60 10 80 30 1.5 1.8 4 1 1.6 20 0\n"
      << "0 3 Car 0 1 0 90 30 110 50 1.5 1.8 4 1 1.6 20 0\n"   // occluded: filtered
      << "0 4 Car 0 0 0 90 30 110 50 1.5 1.8 4 1 1.6 45 0\n";  // too far: filtered
  std::ofstream(d / "seq" / "objects_motion.txt") << "0 1 0 0.0\n0 2 1 5.0\n";
  const ScoreSummary s = scoreSequence((d / "run" / "masks").string(), (d / "seq").string(), ScoreOptions{});
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.frames, 1);
  EXPECT_NEAR(s.median_iou, 1.0, 1e-9);
  EXPECT_EQ(s.label_checked, 2);
  EXPECT_EQ(s.label_correct, 1);
  EXPECT_THROW(scoreSequence((d / "nope").string(), (d / "seq").string(), ScoreOptions{}), std::runtime_error);
  fs::remove_all(d);
}
