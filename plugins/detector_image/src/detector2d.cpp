// Detector2D: OpenCV DNN YOLO-style detector, COCO classes mapped to cars, pedestrians and cyclists.
#include <algorithm>
#include <cmath>
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

constexpr int kYoloxStrides[] = {8, 16, 32};

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
  if (options_.head != "auto" && options_.head != "yolo" && options_.head != "yolox")
    throw std::invalid_argument("head '" + options_.head + "': expected auto, yolo or yolox");
  if (options_.head == "yolox" && !onnx_)
    throw std::invalid_argument("model '" + options_.model + "': head yolox needs an .onnx model");
  head_ = options_.head == "auto" ? (onnx_ ? "" : "yolo") : options_.head;
  if (head_.empty() || head_ == "yolox") {
    // One forward pass on a grey input tells the output's shape: YOLOX's raw head has one row per grid cell.
    head_ = "yolox";  // the letterboxed input both heads accept
    double unused = 1;
    try {
      forward(cv::Mat(options_.input_height, options_.input_width, CV_8UC3, cv::Scalar::all(114)), unused);
    } catch (const cv::Exception& e) {
      throw std::invalid_argument("model '" + options_.model + "' does not run at input " +
                                  std::to_string(options_.input_width) + "x" + std::to_string(options_.input_height) +
                                  " (set input_width and input_height to the size it was exported for): " + e.err);
    }
    const bool grid = outs_.size() == 1 && outs_[0].total() == yoloxCells() * outs_[0].size[outs_[0].dims - 1];
    if (options_.head == "auto") head_ = grid ? "yolox" : "yolo";
    if (head_ == "yolox" && !grid)
      throw std::invalid_argument("model '" + options_.model + "': head yolox expects one output row per cell of the " +
                                  "stride 8, 16 and 32 grids at input " + std::to_string(options_.input_width) + "x" +
                                  std::to_string(options_.input_height) + " (" + std::to_string(yoloxCells()) +
                                  " rows); set input_width and input_height to the size it was exported for");
  }
}

size_t Detector2D::yoloxCells() const {
  size_t cells = 0;
  for (int stride : kYoloxStrides)
    cells += static_cast<size_t>(options_.input_width / stride) * static_cast<size_t>(options_.input_height / stride);
  return cells;
}

void Detector2D::forward(const cv::Mat& bgr, double& letterbox_scale) {
  letterbox_scale = 1;
  if (head_ == "yolox") {
    // Aspect kept, into the top-left corner, the rest grey 114; BGR, 0-255 (YOLOX's own preprocessing).
    letterbox_scale = std::min(static_cast<double>(options_.input_width) / bgr.cols,
                               static_cast<double>(options_.input_height) / bgr.rows);
    const cv::Size scaled(std::max(1, static_cast<int>(bgr.cols * letterbox_scale)),
                          std::max(1, static_cast<int>(bgr.rows * letterbox_scale)));
    letterbox_.create(options_.input_height, options_.input_width, CV_8UC3);
    letterbox_.setTo(cv::Scalar::all(114));
    cv::resize(bgr, letterbox_(cv::Rect(0, 0, scaled.width, scaled.height)), scaled, 0, 0, cv::INTER_LINEAR);
    cv::dnn::blobFromImage(letterbox_, blob_, 1.0, cv::Size(), cv::Scalar(), /*swapRB=*/false, /*crop=*/false);
  } else {
    cv::dnn::blobFromImage(bgr, blob_, 1.0 / 255.0, cv::Size(options_.input_width, options_.input_height), cv::Scalar(),
                           /*swapRB=*/true, /*crop=*/false);
  }
  net_.setInput(blob_);
  net_.forward(outs_, out_names_);
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
  double letterbox_scale = 1;
  forward(*bgr, letterbox_scale);
  const bool yolox = head_ == "yolox";

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
    int stride_index = 0, grid_start = 0;  // yolox: the grid the row belongs to, and its first row
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
      cv::Rect2d box;
      if (yolox) {
        int stride = kYoloxStrides[stride_index], columns = options_.input_width / stride;
        while (r - grid_start >= columns * (options_.input_height / stride)) {
          grid_start += columns * (options_.input_height / stride);
          stride = kYoloxStrides[++stride_index], columns = options_.input_width / stride;
        }
        const int cell = r - grid_start;
        const double cx = (row[0] + cell % columns) * stride, cy = (row[1] + cell / columns) * stride;
        const double w = std::exp(std::min(row[2], 10.0f)) * stride, h = std::exp(std::min(row[3], 10.0f)) * stride;
        box = cv::Rect2d((cx - w / 2) / letterbox_scale, (cy - h / 2) / letterbox_scale, w / letterbox_scale,
                         h / letterbox_scale);
      } else {
        double cx = row[0], cy = row[1], w = row[2], h = row[3];
        if (onnx_ && std::max({cx, cy, w, h}) > 2.0)  // input pixels rather than fractions
          cx /= options_.input_width, w /= options_.input_width, cy /= options_.input_height,
              h /= options_.input_height;
        box = cv::Rect2d((cx - w / 2) * W, (cy - h / 2) * H, w * W, h * H);
      }
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
