// ORB extraction: budgets, spreading, borders, label masks, prepared images, repeatability under rotation
// and scale.
#include <gtest/gtest.h>

#include <numeric>
#include <opencv2/imgproc.hpp>

#include "features/orb_extractor.hpp"
#include "matching/hamming.hpp"
#include "test_util.hpp"

namespace beslam::orb {
namespace {

TEST(OrbExtractor, LevelBudgetsFollowAGeometricSeries) {
  OrbExtractor ex(ExtractorOptions{});
  const auto b = ex.levelBudgets(2000);
  ASSERT_EQ(b.size(), 8u);
  EXPECT_EQ(std::accumulate(b.begin(), b.end(), 0), 2000);
  EXPECT_NEAR(b[0], 2000 * (1 - 1 / 1.2) / (1 - std::pow(1 / 1.2, 8)), 1.0);
  for (int l = 1; l < 7; ++l) EXPECT_NEAR(b[l], b[l - 1] / 1.2, 1.5);
}

TEST(OrbExtractor, QuadtreeKeepsTheBudgetAndSpreadsEvenly) {
  // A dense cluster in one corner and a sparse rest: spreading keeps far more than the cluster's share.
  std::vector<cv::KeyPoint> c;
  cv::RNG rng(1);
  for (int i = 0; i < 1000; ++i) c.emplace_back(rng.uniform(0.f, 50.f), rng.uniform(0.f, 50.f), 7.f, -1, 100.f);
  for (int i = 0; i < 200; ++i) c.emplace_back(rng.uniform(0.f, 400.f), rng.uniform(0.f, 400.f), 7.f, -1, 1.f);
  const auto kept = OrbExtractor::distributeQuadtree(c, 0, 0, 400, 400, 100);
  EXPECT_EQ(kept.size(), 100u);
  int in_cluster = 0;
  for (int i : kept) in_cluster += c[i].pt.x < 50 && c[i].pt.y < 50;
  EXPECT_LT(in_cluster, 30);
}

TEST(OrbExtractor, ExtractsTheBudgetInsideTheBorders) {
  const cv::Mat img = test::texturedImage(1226, 370, 7);
  OrbExtractor ex(ExtractorOptions{});
  const auto f = ex.extract(img, cv::Mat());
  EXPECT_GE(f->size(), 1900u);
  EXPECT_LE(f->size(), 2000u);
  ASSERT_EQ(f->descriptors.rows, static_cast<int>(f->size()));
  for (const auto& kp : f->keypoints) {
    const double s = ex.pyramid().scale[kp.octave];
    EXPECT_GE(kp.pt.x / s, 19 - 1e-3);
    EXPECT_GE(kp.pt.y / s, 19 - 1e-3);
    EXPECT_LT(kp.pt.x / s, std::round(1226 / s) - 19 + 1e-3);
  }
  // Every level contributes.
  std::vector<int> per_level(8, 0);
  for (const auto& kp : f->keypoints) ++per_level[kp.octave];
  for (int l = 0; l < 8; ++l) EXPECT_GT(per_level[l], 0) << "level " << l;
}

TEST(OrbExtractor, LabelMaskRemovesDynamicAndFavoursStaticObjects) {
  const cv::Mat img = test::texturedImage(1226, 370, 8);
  cv::Mat labels(img.size(), CV_16UC1, cv::Scalar(0));
  labels(cv::Rect(100, 50, 300, 250)).setTo(1);      // dynamic
  labels(cv::Rect(700, 100, 150, 150)).setTo(1003);  // static object 3
  OrbExtractor ex(ExtractorOptions{});
  const auto plain = ex.extract(img, cv::Mat());
  const auto f = ex.extract(img, labels);
  int dynamic = 0, on_object = 0, plain_on_object = 0;
  for (size_t i = 0; i < f->size(); ++i) {
    const auto& p = f->keypoints[i].pt;
    dynamic += labels.at<uint16_t>(std::min(369, int(p.y + 0.5f)), std::min(1225, int(p.x + 0.5f))) == 1;
    on_object += f->onStaticObject(i);
    EXPECT_EQ(f->labels[i] >= 1000, f->labels[i] == 1003);
  }
  for (const auto& kp : plain->keypoints)
    plain_on_object += cv::Rect(700, 100, 150, 150).contains(cv::Point(int(kp.pt.x), int(kp.pt.y)));
  EXPECT_EQ(dynamic, 0);
  EXPECT_GT(on_object, plain_on_object * 2) << "static objects get a larger share of the budget";
  EXPECT_LE(on_object, 0.3 * 2000 + 10);
}

// prepare() (pyramids and corners ahead, from borrowed pixels) changes nothing extract() finds, with or
// without a label mask, on grey and colour images.
TEST(OrbExtractor, PreparedImagesGiveTheSameFeatures) {
  const cv::Mat grey = test::texturedImage(1226, 370, 11);
  cv::Mat colour;
  cv::cvtColor(grey, colour, cv::COLOR_GRAY2BGR);
  cv::Mat labels(grey.size(), CV_16UC1, cv::Scalar(0));
  labels(cv::Rect(100, 50, 300, 250)).setTo(1);
  labels(cv::Rect(700, 100, 150, 150)).setTo(1003);
  OrbExtractor ex(ExtractorOptions{});
  for (const cv::Mat& image : {grey, colour})
    for (const cv::Mat& mask : {cv::Mat(), labels}) {
      cv::Mat borrowed = image.clone();
      const auto prepared = ex.prepare(borrowed);
      borrowed.setTo(0);  // the prepared image owns its pixels
      const auto a = ex.extract(image, mask), b = ex.extract(image, mask, 0, prepared.get());
      ASSERT_EQ(a->size(), b->size());
      ASSERT_GT(a->size(), 1000u);
      for (size_t i = 0; i < a->size(); ++i) {
        EXPECT_EQ(a->keypoints[i].pt, b->keypoints[i].pt);
        EXPECT_EQ(a->keypoints[i].angle, b->keypoints[i].angle);
        EXPECT_EQ(a->labels[i], b->labels[i]);
      }
      EXPECT_EQ(cv::norm(a->descriptors, b->descriptors, cv::NORM_HAMMING), 0);
    }
  // A prepared image of another size is refused, not used.
  EXPECT_THROW(ex.extract(grey(cv::Rect(0, 0, 600, 300)).clone(), cv::Mat(), 0, ex.prepare(grey).get()),
               std::invalid_argument);
}

// Fraction of keypoints of A whose nearest descriptor in B lies where the known warp puts them.
double repeatability(const cv::Mat& a, const cv::Mat& b, const cv::Mat& warp_ab, double tol) {
  OrbExtractor ex(ExtractorOptions{});
  const auto fa = ex.extract(a, cv::Mat(), 1000), fb = ex.extract(b, cv::Mat(), 1000);
  int good = 0, total = 0;
  for (size_t i = 0; i < fa->size(); ++i) {
    const cv::Point2f p = fa->keypoints[i].pt;
    const double x = warp_ab.at<double>(0, 0) * p.x + warp_ab.at<double>(0, 1) * p.y + warp_ab.at<double>(0, 2);
    const double y = warp_ab.at<double>(1, 0) * p.x + warp_ab.at<double>(1, 1) * p.y + warp_ab.at<double>(1, 2);
    if (x < 40 || y < 40 || x > b.cols - 40 || y > b.rows - 40) continue;
    ++total;
    int best = 256;
    size_t best_j = 0;
    for (size_t j = 0; j < fb->size(); ++j) {
      const int d = hamming(fa->descriptor(i), fb->descriptor(j));
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    const cv::Point2f q = fb->keypoints[best_j].pt;
    if (best <= 64 && std::hypot(q.x - x, q.y - y) < tol * ex.pyramid().scale[fa->keypoints[i].octave]) ++good;
  }
  return total ? static_cast<double>(good) / total : 0.0;
}

// repeatability() between a textured image (seed) and itself rotated by angle_deg and scaled about its centre.
double warpedRepeatability(int seed, double angle_deg, double scale) {
  const cv::Mat a = test::texturedImage(640, 480, seed);
  const cv::Mat warp = cv::getRotationMatrix2D(cv::Point2f(320, 240), angle_deg, scale);
  cv::Mat b;
  cv::warpAffine(a, b, warp, a.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return repeatability(a, b, warp, 3.0);
}

TEST(OrbExtractor, RepeatableUnderRotation) { EXPECT_GT(warpedRepeatability(9, 30.0, 1.0), 0.5); }

TEST(OrbExtractor, RepeatableUnderScale) { EXPECT_GT(warpedRepeatability(10, 0.0, 1.3), 0.4); }

TEST(FeatureGrid, QueryFindsExactlyTheKeypointsInTheWindow) {
  FeatureSet f;
  f.width = 640;
  f.height = 480;
  cv::RNG rng(3);
  for (int i = 0; i < 500; ++i)
    f.keypoints.emplace_back(rng.uniform(0.f, 640.f), rng.uniform(0.f, 480.f), 7.f, 0, 1.f, rng.uniform(0, 8));
  f.buildGrid();
  const auto got = f.query(300, 200, 40, 2, 5);
  int expected = 0;
  for (const auto& kp : f.keypoints)
    expected += std::fabs(kp.pt.x - 300) <= 40 && std::fabs(kp.pt.y - 200) <= 40 && kp.octave >= 2 && kp.octave <= 5;
  EXPECT_EQ(static_cast<int>(got.size()), expected);
}

}  // namespace
}  // namespace beslam::orb
