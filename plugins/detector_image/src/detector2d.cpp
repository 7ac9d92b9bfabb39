// Detector2D: OpenCV DNN YOLO-style detector, COCO classes mapped to cars, pedestrians and cyclists.
#include <algorithm>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "beslam/detector_image/image_detector.hpp"

namespace beslam::detector_image {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  if (s.size() < suffix.size()) return false;
  return std::equal(suffix.rbegin(), suffix.rend(), s.rbegin(),
                    [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == b; });
}

void requireReadable(const std::string& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  char c;
  if (!in || !in.get(c))
    throw std::invalid_argument(std::string(what) + " '" + path + "' is missing, unreadable or empty");
}

bool contains(const std::vector<int>& v, int x) { return std::find(v.begin(), v.end(), x) != v.end(); }

double overlapOfSecond(const cv::Rect2d& a, const cv::Rect2d& b) {  // |a & b| / |b|
  const double inter = (a & b).area();
  return b.area() > 0 ? inter / b.area() : 0;
}

}  // namespace

Detector2D::Detector2D(const DnnOptions& options) : options_(options) {
  if (options_.model.empty())
    throw std::invalid_argument(
        "no model: set `model` to a Darknet .cfg (with `weights`) or an .onnx file, e.g. "
        "../../shared/models/yolo-fastest-1.1/yolo-fastest-1.1.cfg");
  if (options_.input_width < 32 || options_.input_height < 32 || options_.input_width % 32 != 0 ||
      options_.input_height % 32 != 0)
    throw std::invalid_argument("input_width and input_height must be positive multiples of 32");
  if (!(options_.score_threshold > 0 && options_.score_threshold < 1) ||
      !(options_.nms_threshold > 0 && options_.nms_threshold <= 1))
    throw std::invalid_argument("score_threshold must be in (0, 1) and nms_threshold in (0, 1]");
  onnx_ = endsWith(options_.model, ".onnx");
  requireReadable(options_.model, "model file");
  if (!onnx_) {
    if (!endsWith(options_.model, ".cfg"))
      throw std::invalid_argument("model '" + options_.model + "': expected a Darknet .cfg or an .onnx file");
    if (options_.weights.empty())
      throw std::invalid_argument("model '" + options_.model +
                                  "' is a Darknet .cfg: set `weights` to its .weights file");
    requireReadable(options_.weights, "weights file");
  }
  try {
    net_ = onnx_ ? cv::dnn::readNetFromONNX(options_.model)
                 : cv::dnn::readNetFromDarknet(options_.model, options_.weights);
  } catch (const cv::Exception& e) {
    throw std::invalid_argument("cannot load model '" + options_.model +
                                (onnx_ ? "" : "' with weights '" + options_.weights) + "': " + e.err);
  }
  if (net_.empty()) throw std::invalid_argument("cannot load model '" + options_.model + "': empty network");
  net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  out_names_ = net_.getUnconnectedOutLayersNames();
}

std::vector<Detection2D> Detector2D::detect(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("detector_image: empty image");
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    throw std::invalid_argument("detector_image: expected an 8-bit grey or BGR image");
  const cv::Mat* bgr = &image;
  if (image.channels() == 1) {
    cv::cvtColor(image, bgr_, cv::COLOR_GRAY2BGR);
    bgr = &bgr_;
  }
  cv::dnn::blobFromImage(*bgr, blob_, 1.0 / 255.0, cv::Size(options_.input_width, options_.input_height), cv::Scalar(),
                         /*swapRB=*/true, /*crop=*/false);
  net_.setInput(blob_);
  net_.forward(outs_, out_names_);

  // Candidates per wanted COCO class.
  const double W = image.cols, H = image.rows;
  struct Candidates {
    std::vector<cv::Rect2d> boxes;
    std::vector<float> scores;
  };
  Candidates cars, people, cycles;
  for (cv::Mat out : outs_) {
    if (out.dims > 2) out = out.reshape(1, static_cast<int>(out.total() / out.size[out.dims - 1]));
    if (out.cols < 6) continue;
    for (int r = 0; r < out.rows; ++r) {
      const float* row = out.ptr<float>(r);
      const float objectness = row[4];
      if (onnx_ && objectness < options_.score_threshold) continue;
      int best = -1;
      float best_score = 0;
      for (int c = 5; c < out.cols; ++c)
        if (row[c] > best_score) best_score = row[c], best = c - 5;
      const float score = onnx_ ? best_score * objectness : best_score;  // OpenCV's Darknet output is already P(class)
      if (best < 0 || score < options_.score_threshold) continue;
      double cx = row[0], cy = row[1], w = row[2], h = row[3];
      if (onnx_ && std::max({cx, cy, w, h}) > 2.0)  // input pixels rather than fractions
        cx /= options_.input_width, w /= options_.input_width, cy /= options_.input_height, h /= options_.input_height;
      cv::Rect2d box((cx - w / 2) * W, (cy - h / 2) * H, w * W, h * H);
      box &= cv::Rect2d(0, 0, W, H);
      if (box.area() <= 0) continue;
      Candidates* target = contains(options_.car_classes, best)          ? &cars
                           : contains(options_.pedestrian_classes, best) ? &people
                           : contains(options_.cycle_classes, best)      ? &cycles
                                                                         : nullptr;
      if (target == nullptr) continue;
      target->boxes.push_back(box);
      target->scores.push_back(score);
    }
  }
  auto nms = [&](Candidates& c) {
    std::vector<int> keep;
    cv::dnn::NMSBoxes(c.boxes, c.scores, static_cast<float>(options_.score_threshold),
                      static_cast<float>(options_.nms_threshold), keep);
    if (options_.containment_threshold <= 0) return keep;
    // A box mostly inside another of its class is a part of the same object (its top, its front): keep the
    // enclosing box, whose bottom edge is the object's, with the better of the two scores.
    std::vector<bool> dropped(keep.size(), false);
    for (size_t a = 0; a < keep.size(); ++a)
      for (size_t b = 0; b < keep.size(); ++b) {
        if (a == b || dropped[a] || dropped[b]) continue;
        const cv::Rect2d& inner = c.boxes[keep[a]];
        const cv::Rect2d& outer = c.boxes[keep[b]];
        if (inner.area() > outer.area() || overlapOfSecond(outer, inner) < options_.containment_threshold) continue;
        dropped[a] = true;
        c.scores[keep[b]] = std::max(c.scores[keep[b]], c.scores[keep[a]]);
      }
    std::vector<int> out;
    for (size_t a = 0; a < keep.size(); ++a)
      if (!dropped[a]) out.push_back(keep[a]);
    return out;
  };
  std::vector<Detection2D> detections;
  for (int i : nms(cars)) detections.push_back({BESLAM_CLASS_CAR, cars.scores[i], cars.boxes[i]});
  std::vector<int> kept_people = nms(people), kept_cycles = nms(cycles);
  std::vector<bool> rider(kept_people.size(), false);
  for (int b : kept_cycles) {  // a person whose box covers the upper part of a bicycle/motorbike rides it
    int best = -1;
    double best_overlap = 0.3;
    for (size_t p = 0; p < kept_people.size(); ++p) {
      if (rider[p]) continue;
      const cv::Rect2d& person = people.boxes[kept_people[p]];
      const cv::Rect2d& cycle = cycles.boxes[b];
      const double overlap = overlapOfSecond(person, cycle);
      const double person_cx = person.x + person.width / 2;
      if (overlap > best_overlap && person_cx > cycle.x && person_cx < cycle.x + cycle.width)
        best_overlap = overlap, best = static_cast<int>(p);
    }
    if (best < 0) continue;  // a parked bicycle is neither a cyclist nor a pedestrian
    rider[best] = true;
    const int p = kept_people[best];
    detections.push_back(
        {BESLAM_CLASS_CYCLIST, 0.5f * (people.scores[p] + cycles.scores[b]), people.boxes[p] | cycles.boxes[b]});
  }
  for (size_t p = 0; p < kept_people.size(); ++p)
    if (!rider[p])
      detections.push_back({BESLAM_CLASS_PEDESTRIAN, people.scores[kept_people[p]], people.boxes[kept_people[p]]});
  return detections;
}

}  // namespace beslam::detector_image
