// ORB extraction: budgets, spreading, borders, label masks, prepared images, repeatability under rotation
// and scale.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <tuple>

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

// The static objects of a mask are one box per label (>= 1000); searched apart (parked cars on either side
// of the road), they give the corners of one search over the box of all of them, in the same order.
TEST(OrbExtractor, StaticObjectsSearchedApartGiveTheCornersOfOneSearchOverAll) {
  const cv::Mat img = test::texturedImage(1226, 370, 11);
  cv::Mat labels(img.size(), CV_16UC1, cv::Scalar(0));
  const std::vector<cv::Rect> boxes = {
      {60, 150, 260, 120}, {900, 140, 240, 150}, {500, 170, 90, 70}, {560, 200, 80, 80}};
  for (size_t i = 0; i < boxes.size(); ++i) labels(boxes[i]).setTo(1000 + static_cast<int>(i));
  labels(cv::Rect(540, 150, 30, 20)).setTo(1);  // a dynamic pixel block inside the box of all
  const StaticRegions regions = OrbExtractor::staticRegions(labels);
  ASSERT_EQ(regions.objects.size(), 4u);
  cv::Rect all;
  for (size_t i = 0; i < boxes.size(); ++i) {  // objects 2 and 3 overlap: 3 covers part of 2, not its extent
    EXPECT_NE(std::find(regions.objects.begin(), regions.objects.end(), boxes[i]), regions.objects.end())
        << "object " << i;
    all |= boxes[i];
  }
  EXPECT_EQ(regions.all, all);

  OrbExtractor ex(ExtractorOptions{});
  const auto prepared = ex.prepare(img);
  for (int level : {0, 3}) {
    const cv::Mat& level_image = prepared->level_images[level];
    const double s = ex.pyramid().scale[level];
    // The one search over all objects, as the extractor did it before searching them apart.
    const cv::Rect roi = cv::Rect(static_cast<int>(all.x / s) - 3, static_cast<int>(all.y / s) - 3,
                                  static_cast<int>(all.width / s) + 8, static_cast<int>(all.height / s) + 8) &
                         cv::Rect(0, 0, level_image.cols, level_image.rows);
    std::vector<cv::KeyPoint> whole;
    cv::FAST(level_image(roi), whole, 7, true);
    const auto onObject = [&](const cv::KeyPoint& kp) {  // the level-0 pixel a corner is labelled by
      const int x = static_cast<int>((kp.pt.x + 0.5) * s), y = static_cast<int>((kp.pt.y + 0.5) * s);
      return x < labels.cols && y < labels.rows && labels.at<uint16_t>(y, x) >= 1000;
    };
    std::vector<cv::KeyPoint> expected, got;
    for (cv::KeyPoint kp : whole) {
      kp.pt += cv::Point2f(static_cast<float>(roi.x), static_cast<float>(roi.y));
      if (onObject(kp)) expected.push_back(kp);
    }
    for (const cv::KeyPoint& kp : OrbExtractor::staticObjectCorners(level_image, s, regions, 7))
      if (onObject(kp)) got.push_back(kp);
    ASSERT_GT(expected.size(), 100u) << "level " << level;
    ASSERT_EQ(got.size(), expected.size()) << "level " << level;
    for (size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].pt, expected[i].pt) << "level " << level << " corner " << i;
      EXPECT_EQ(got[i].response, expected[i].response) << "level " << level << " corner " << i;
    }
  }
}

// A keypoint's angle is the intensity centroid's over the disc of radius 15 around it on its level.
TEST(OrbExtractor, AnglesAreTheIntensityCentroidsOverTheDisc) {
  const cv::Mat img = test::texturedImage(1226, 370, 12);
  OrbExtractor ex(ExtractorOptions{});
  const auto prepared = ex.prepare(img);
  const auto f = ex.extract(img, cv::Mat(), 0, prepared.get());
  ASSERT_GT(f->size(), 1000u);
  for (const cv::KeyPoint& kp : f->keypoints) {
    const cv::Mat& level = prepared->level_images[kp.octave];
    const double s = ex.pyramid().scale[kp.octave];
    const int cx = cvRound((kp.pt.x + 0.5) / s - 0.5), cy = cvRound((kp.pt.y + 0.5) / s - 0.5);
    int m10 = 0, m01 = 0;
    for (int v = -15; v <= 15; ++v) {
      const int d = static_cast<int>(std::floor(std::sqrt(15 * 15 - v * v + 0.5)));
      for (int u = -d; u <= d; ++u) {
        const int value = level.at<uint8_t>(cy + v, cx + u);
        m10 += u * value;
        m01 += v * value;
      }
    }
    ASSERT_EQ(kp.angle, cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10)))
        << "keypoint at " << kp.pt << " level " << kp.octave;
  }
}

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

TEST(FeatureGrid, CellRangeIsTheFloorOfTheWindowInCells) {
  // The columns and rows of std::floor(coordinate / cell size), clamped to the grid, for negative fractions,
  // exact cell edges and their neighbours, and coordinates far beyond the image; none for a NaN bound.
  FeatureSet f;
  f.width = 1241;
  f.height = 376;
  f.keypoints.emplace_back(10.f, 10.f, 7.f);
  f.buildGrid();
  const float inv_w = static_cast<float>(FeatureGrid::kCols) / 1241.f;
  const float inv_h = static_cast<float>(FeatureGrid::kRows) / 376.f;
  const auto floorIn = [](float v, int lo, int hi) {  // no float-to-int conversion out of range
    const float f = std::floor(v);
    return f < static_cast<float>(lo) ? lo : f > static_cast<float>(hi) ? hi + 1 : static_cast<int>(f);
  };
  std::vector<float> xs = {-1e12f, -3e9f, -19.4f, -19.39f, -0.5f,  -0.f,   0.f,  0.2f,
                           19.39f, 19.4f, 620.5f, 1240.9f, 1241.f, 5000.f, 3e9f, 1e12f};
  cv::RNG rng(11);
  for (int i = 0; i < 2000; ++i) xs.push_back(rng.uniform(-100.f, 1400.f));
  for (int k = 0; k <= FeatureGrid::kCols; ++k) {  // the column edges and their neighbours
    const float edge = static_cast<float>(k) / inv_w;
    xs.insert(xs.end(), {edge, std::nextafter(edge, -1e30f), std::nextafter(edge, 1e30f)});
  }
  for (float x0 : xs)
    for (float x1 : {x0, x0 + 25.f, 1300.f, -5.f}) {
      const float y0 = x0 * 0.3f, y1 = x1 * 0.3f;
      int c0 = 0, c1 = 0, r0 = 0, r1 = 0;
      const bool any = f.grid.cellRange(x0, y0, x1, y1, c0, c1, r0, r1);
      const int e_c0 = std::max(0, floorIn(x0 * inv_w, -1, FeatureGrid::kCols));
      const int e_c1 = std::min(FeatureGrid::kCols - 1, floorIn(x1 * inv_w, -1, FeatureGrid::kCols));
      const int e_r0 = std::max(0, floorIn(y0 * inv_h, -1, FeatureGrid::kRows));
      const int e_r1 = std::min(FeatureGrid::kRows - 1, floorIn(y1 * inv_h, -1, FeatureGrid::kRows));
      ASSERT_EQ(any, e_c0 <= e_c1 && e_r0 <= e_r1) << "x0 " << x0 << " x1 " << x1;
      if (any) {
        EXPECT_EQ(std::make_tuple(c0, c1, r0, r1), std::make_tuple(e_c0, e_c1, e_r0, e_r1)) << "x0 " << x0;
      }
    }
  int c0 = 0, c1 = 0, r0 = 0, r1 = 0;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(f.grid.cellRange(nan, 0.f, 100.f, 100.f, c0, c1, r0, r1));
  EXPECT_FALSE(f.grid.cellRange(0.f, 0.f, 100.f, nan, c0, c1, r0, r1));
}

}  // namespace
}  // namespace beslam::orb
