// ORB features the ORB-SLAM way: an 8-level pyramid (scale 1.2, linear interpolation), FAST per ~30 px
// cell (threshold 20, 7 where a cell finds nothing), quadtree spreading to each level's geometric-series
// budget, intensity-centroid orientation and rBRIEF descriptors (OpenCV's learned pattern via
// cv::ORB::compute on our own keypoints). The levels are searched in parallel; the result does not depend
// on the threads.
//
// Label mask (CV_16UC1): pixels == 1 get no features; pixels >= 1000 (static objects) are searched with a
// lower FAST threshold and get up to a configurable share of every level's budget.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

#include "beslam_orb/options.hpp"
#include "features/feature_set.hpp"
#include "features/scale_pyramid.hpp"

namespace beslam::orb {

// The part of an extraction that needs no label mask: the grey image, both pyramids, each level's FAST
// corners at the initial threshold and, in the cells where those found nothing, at the fallback threshold
// (a mask can only empty more cells; those are searched when the mask is known). Owns its pixels (the
// input image may go away).
struct PreparedLevel {
  std::vector<cv::KeyPoint> corners;                    // initial threshold, level pixels
  std::vector<char> cell_searched;                      // per FAST cell: fallback corners below are known
  std::vector<std::vector<cv::KeyPoint>> cell_corners;  // per FAST cell, inside the cell and the border
};
struct PreparedImage {
  cv::Mat grey;
  std::vector<cv::Mat> level_images;     // INTER_LINEAR pyramid: where corners are found
  std::vector<cv::Mat> describe_images;  // INTER_LINEAR_EXACT pyramid: where rBRIEF is read
  std::vector<PreparedLevel> levels;
};

// Where a label mask has static objects (labels >= 1000), level-0 pixels: each object's bounding box and
// the box of all of them.
struct StaticRegions {
  cv::Rect all;
  std::vector<cv::Rect> objects;
};

class OrbExtractor {
 public:
  explicit OrbExtractor(const ExtractorOptions& options);

  // image: CV_8UC1 or CV_8UC3 (BGR); labels: CV_16UC1 of the same size or empty.
  // budget <= 0 means options.features. prepared: prepare(image) done ahead (e.g. on another thread);
  // the features are the same with it as without.
  std::shared_ptr<FeatureSet> extract(const cv::Mat& image, const cv::Mat& labels, int budget = 0,
                                      const PreparedImage* prepared = nullptr) const;
  // The label-independent first part of extract(). Const and thread-safe: may run while another thread
  // extracts.
  std::shared_ptr<const PreparedImage> prepare(const cv::Mat& image) const;

  const ScalePyramid& pyramid() const { return pyramid_; }
  const ExtractorOptions& options() const { return options_; }

  // Level budgets for n features: a geometric series summing to n.
  std::vector<int> levelBudgets(int n) const;

  // Keep at most n of the candidates, spread by a quadtree over [x0,x1) x [y0,y1): the strongest
  // response per leaf. Returns indices into candidates.
  static std::vector<int> distributeQuadtree(const std::vector<cv::KeyPoint>& candidates, float x0, float y0, float x1,
                                             float y1, int n);

  // The static objects of a CV_16UC1 label mask, one box per label value >= 1000.
  static StaticRegions staticRegions(const cv::Mat& labels);
  // FAST at `threshold` (non-maximum suppressed) on the static objects of one pyramid level (scale s):
  // the corners, in raster order, that one search over the level rect of all objects (`regions.all`, 3 px
  // before and 5 after) finds inside the objects' level boxes, without searching the space between
  // objects that lie apart (parked cars on either side of the road). Level pixels.
  static std::vector<cv::KeyPoint> staticObjectCorners(const cv::Mat& level_image, double s,
                                                       const StaticRegions& regions, int threshold);

 private:
  float icAngle(const cv::Mat& image, const cv::Point2f& pt) const;
  // grey (its pixels referenced, not copied) and both pyramids, without corners.
  PreparedImage pyramids(const cv::Mat& grey) const;
  // One pyramid level's keypoints (level pixels, oriented) and the labels under them, n_level at most.
  // prepared: the level's corners found ahead (prepare()), else all are found here.
  void detectLevel(const cv::Mat& level_image, int level, const cv::Mat& labels, const StaticRegions& static_regions,
                   int n_level, const PreparedLevel* prepared, std::vector<cv::KeyPoint>& level_kps,
                   std::vector<uint16_t>& level_labels) const;

  ExtractorOptions options_;
  ScalePyramid pyramid_;
  std::vector<int> umax_;  // half-widths of the circular orientation patch
  // The orientation patch as rows of 32 pixels (u = -16..15, v = -15..15): per pixel, u inside the disc
  // and 0 outside (for m10), and 1 inside and 0 outside (for the row sums of m01).
  static constexpr int kIcRows = 31, kIcRowWidth = 32, kIcRowOffset = 16;
  std::array<std::array<int16_t, kIcRowWidth>, kIcRows> ic_u_weights_{}, ic_disc_{};
  std::vector<cv::Ptr<cv::ORB>> describers_;  // rBRIEF, one single-level cv::ORB per pyramid level
};

}  // namespace beslam::orb
