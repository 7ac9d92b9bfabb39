// ORB features the ORB-SLAM way: an 8-level pyramid (scale 1.2, linear interpolation), FAST per ~30 px
// cell (threshold 20, 7 where a cell finds nothing), quadtree spreading to each level's geometric-series
// budget, intensity-centroid orientation and rBRIEF descriptors (OpenCV's learned pattern via
// cv::ORB::compute on our own keypoints). The levels are searched in parallel; the result does not depend
// on the threads.
//
// Label mask (CV_16UC1): pixels == 1 get no features; pixels >= 1000 (static objects) are searched with a
// lower FAST threshold and get up to a configurable share of every level's budget.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

#include "beslam_orb/orb_slam.hpp"  // ExtractorOptions
#include "features/feature_set.hpp"
#include "features/scale_pyramid.hpp"

namespace beslam::orb {

class OrbExtractor {
 public:
  explicit OrbExtractor(const ExtractorOptions& options);

  // image: CV_8UC1 or CV_8UC3 (BGR); labels: CV_16UC1 of the same size or empty.
  // budget <= 0 means options.features.
  std::shared_ptr<FeatureSet> extract(const cv::Mat& image, const cv::Mat& labels, int budget = 0) const;

  const ScalePyramid& pyramid() const { return pyramid_; }
  const ExtractorOptions& options() const { return options_; }

  // Level budgets for n features: a geometric series summing to n.
  std::vector<int> levelBudgets(int n) const;

  // Keep at most n of the candidates, spread by a quadtree over [x0,x1) x [y0,y1): the strongest
  // response per leaf. Returns indices into candidates.
  static std::vector<int> distributeQuadtree(const std::vector<cv::KeyPoint>& candidates, float x0, float y0, float x1,
                                             float y1, int n);

 private:
  float icAngle(const cv::Mat& image, const cv::Point2f& pt) const;
  // One pyramid level's keypoints (level pixels, oriented) and the labels under them, n_level at most.
  void detectLevel(const cv::Mat& level_image, int level, const cv::Mat& labels, const cv::Rect& static_box,
                   int n_level, std::vector<cv::KeyPoint>& level_kps, std::vector<uint16_t>& level_labels) const;

  ExtractorOptions options_;
  ScalePyramid pyramid_;
  std::vector<int> umax_;                     // half-widths of the circular orientation patch
  std::vector<cv::Ptr<cv::ORB>> describers_;  // rBRIEF, one single-level cv::ORB per pyramid level
};

}  // namespace beslam::orb
