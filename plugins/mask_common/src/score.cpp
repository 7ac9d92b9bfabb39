#include "beslam/mask_common/score.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

#include "beslam/formats/labels.hpp"

namespace fs = std::filesystem;

namespace beslam::mask {

double maskIou(const cv::Mat& a, const cv::Mat& b) {
  CV_Assert(a.size() == b.size());
  cv::Mat ia = a != 0, ib = b != 0, inter, uni;
  cv::bitwise_and(ia, ib, inter);
  cv::bitwise_or(ia, ib, uni);
  const int u = cv::countNonZero(uni);
  return u ? static_cast<double>(cv::countNonZero(inter)) / u : 0.0;
}

double objectIou(const cv::Mat& pred, const cv::Mat& instance, int track_id, int* label) {
  CV_Assert(pred.type() == CV_16UC1 && instance.type() == CV_16UC1 && pred.size() == instance.size());
  const cv::Mat gt = instance == track_id;
  std::map<int, int> hist;
  for (int y = 0; y < pred.rows; ++y) {
    const uint16_t* p = pred.ptr<uint16_t>(y);
    const uint8_t* g = gt.ptr<uint8_t>(y);
    for (int x = 0; x < pred.cols; ++x)
      if (g[x] && p[x]) ++hist[p[x]];
  }
  int best = 0, best_n = 0;
  for (const auto& [l, n] : hist)
    if (n > best_n) best = l, best_n = n;
  if (label) *label = best;
  if (best == 0) return 0.0;
  cv::Mat region = pred == best;
  if (best == 1) {
    // Dynamic pixels carry no identity: the connected components that touch the object.
    cv::Mat cc;
    const int n = cv::connectedComponents(region, cc, 8, CV_32S);
    std::vector<uint8_t> keep(n, 0);
    for (int y = 0; y < cc.rows; ++y) {
      const int* c = cc.ptr<int>(y);
      const uint8_t* g = gt.ptr<uint8_t>(y);
      for (int x = 0; x < cc.cols; ++x)
        if (g[x] && c[x] > 0) keep[c[x]] = 1;
    }
    for (int y = 0; y < cc.rows; ++y) {
      const int* c = cc.ptr<int>(y);
      uint8_t* r = region.ptr<uint8_t>(y);
      for (int x = 0; x < cc.cols; ++x) r[x] = keep[c[x]] ? 255 : 0;
    }
  }
  return maskIou(region, gt);
}

namespace {

std::string frameName(int64_t frame) {
  std::string s = std::to_string(frame);
  return std::string(s.size() < 6 ? 6 - s.size() : 0, '0') + s + ".png";
}

cv::Mat readLabel16(const std::string& path) {
  if (!fs::exists(path)) throw std::runtime_error(path + ": missing");
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty()) throw std::runtime_error(path + ": cannot decode");
  if (m.type() != CV_16UC1) throw std::runtime_error(path + ": expected a 16-bit single-channel PNG");
  return m;
}

}  // namespace

void summarise(ScoreSummary& s) {
  std::vector<double> v;
  s.label_checked = s.label_correct = 0;
  for (const ObjectScore& o : s.objects) {
    v.push_back(o.iou);
    if (o.motion_known) {
      ++s.label_checked;
      if (o.moving ? o.predicted_label == 1 : o.predicted_label >= 1000) ++s.label_correct;
    }
  }
  if (v.empty()) return;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  s.median_iou = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  double sum = 0;
  for (double x : v) sum += x;
  s.mean_iou = sum / n;
  s.p10_iou = v[static_cast<size_t>(0.1 * (n - 1))];
}

std::map<std::pair<int64_t, int64_t>, bool> readObjectMotionIfPresent(const std::string& path) {
  if (!fs::exists(path)) return {};
  return formats::readObjectMotion(path);
}

ScoreSummary scoreSequence(const std::string& masks_dir, const std::string& sequence_dir, const ScoreOptions& options) {
  const fs::path seq(sequence_dir);
  if (!fs::is_directory(seq / "instance"))
    throw std::runtime_error((seq / "instance").string() + ": missing (ground-truth instance masks)");
  if (!fs::is_directory(masks_dir)) throw std::runtime_error(masks_dir + ": missing (the run's masks folder)");
  std::string label_file;
  if (fs::is_directory(seq / "label_02"))
    for (const auto& e : fs::directory_iterator(seq / "label_02"))
      if (e.path().extension() == ".txt") label_file = e.path().string();
  if (label_file.empty()) throw std::runtime_error((seq / "label_02").string() + ": no tracking label file");
  std::map<int64_t, std::vector<formats::TrackingLabel>> labels;
  for (auto& l : formats::readTrackingLabels(label_file)) labels[l.frame].push_back(std::move(l));

  const std::map<std::pair<int64_t, int64_t>, bool> moving =
      readObjectMotionIfPresent((seq / "objects_motion.txt").string());

  ScoreSummary summary;
  for (const auto& e : fs::directory_iterator(masks_dir)) {
    if (e.path().extension() != ".png") continue;
    const std::string stem = e.path().stem().string();
    if (stem.empty() || stem.find_first_not_of("0123456789") != std::string::npos) continue;
    const int64_t frame = std::stoll(stem);
    if (frame < options.first || (options.last >= 0 && frame > options.last)) continue;
    const cv::Mat pred = readLabel16(e.path().string());
    const cv::Mat inst = readLabel16((seq / "instance" / frameName(frame)).string());
    if (pred.size() != inst.size())
      throw std::runtime_error(e.path().string() + ": size differs from the instance mask");
    ++summary.frames;
    for (const formats::TrackingLabel& l : labels[frame]) {
      const auto& o = l.object;
      if (std::find(options.types.begin(), options.types.end(), o.type) == options.types.end()) continue;
      const double dist = o.p_cam_bottom.norm();
      if (dist > options.max_distance || o.occluded > options.max_occlusion || o.truncated > options.max_truncation)
        continue;
      ObjectScore s;
      s.frame = frame;
      s.track_id = static_cast<int>(l.track_id);
      s.distance = dist;
      s.gt_pixels = cv::countNonZero(inst == s.track_id);
      if (s.gt_pixels < options.min_pixels) continue;
      const auto it = moving.find({frame, l.track_id});
      s.motion_known = it != moving.end();
      s.moving = s.motion_known && it->second;
      s.iou = objectIou(pred, inst, s.track_id, &s.predicted_label);
      summary.objects.push_back(s);
    }
  }
  std::sort(summary.objects.begin(), summary.objects.end(), [](const ObjectScore& a, const ObjectScore& b) {
    return std::tie(a.frame, a.track_id) < std::tie(b.frame, b.track_id);
  });
  summarise(summary);
  return summary;
}

}  // namespace beslam::mask
