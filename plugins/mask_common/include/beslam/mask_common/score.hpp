// Scoring label masks (as a run writes them: masks/NNNNNN.png, 16-bit, 0 background, 1 dynamic, 1000 +
// track id static) against a synthetic sequence's ground truth (`beslam synth` layout:
// sequences/NN/instance/NNNNNN.png with track ids, label_02/NN.txt, objects_motion.txt).
//
// Per ground-truth object and frame that passes the filter (type, distance, occlusion, truncation), the
// predicted region is the label most frequent on the object's pixels: a static label's pixels, or, for
// the dynamic label, the connected components of dynamic pixels touching the object. IoU of that region
// with the object's instance pixels (0 when nothing is predicted there). The label is also checked:
// moving objects should be dynamic, parked ones static.
#pragma once

#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace beslam::mask {

struct ScoreOptions {
  double max_distance = 30.0;  // m, camera to the box's bottom centre
  int max_occlusion = 0;       // KITTI occluded field: 0 = unoccluded only
  double max_truncation = 0.1;
  int min_pixels = 50;  // instance pixels
  std::vector<std::string> types = {"Car", "Van"};
  int64_t first = 0, last = -1;  // frame range (last inclusive, -1: all)
};

struct ObjectScore {
  int64_t frame = 0;
  int track_id = 0;
  double distance = 0;
  bool moving = false;
  bool motion_known = false;
  int predicted_label = 0;  // the most frequent label on the object (0: none)
  double iou = 0;
  int gt_pixels = 0;
};

struct ScoreSummary {
  std::vector<ObjectScore> objects;
  int frames = 0;
  double median_iou = 0, mean_iou = 0, p10_iou = 0;
  int label_checked = 0, label_correct = 0;  // objects with known motion, and those labelled right
};

double maskIou(const cv::Mat& a, const cv::Mat& b);  // two CV_8UC1 masks (nonzero = inside)

// One frame: pred CV_16UC1 label mask, instance CV_16UC1 ids. Returns the region of `track_id` and its
// most frequent predicted label (via *label).
double objectIou(const cv::Mat& pred, const cv::Mat& instance, int track_id, int* label = nullptr);

// Reads `masks_dir`/NNNNNN.png and the sequence folder (the one holding instance/, label_02/,
// objects_motion.txt). Throws std::runtime_error naming the file on a missing or malformed input.
ScoreSummary scoreSequence(const std::string& masks_dir, const std::string& sequence_dir, const ScoreOptions& options);

void summarise(ScoreSummary& summary);

// formats::readObjectMotion (objects_motion.txt, (frame, track id) -> moving), except that an absent file
// gives an empty map.
std::map<std::pair<int64_t, int64_t>, bool> readObjectMotionIfPresent(const std::string& path);

}  // namespace beslam::mask
