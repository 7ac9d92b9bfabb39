// detector_image_eval: scores the monocular detector's lifted distances against KITTI tracking labels.
//
//   detector_image_eval <sequence folder> <tracking labels.txt> <model.cfg|.onnx> [weights] [max_distance_m=20]
//                       [camera_height=1.65] [score_threshold=0.3]
//
// Reads image_2/ (else image_0/) and P2 (else P0) from calib.txt of a KITTI-odometry-layout folder (what
// `beslam synth` writes), runs Detector2D + GroundLifter on every frame, matches car boxes to Car labels by
// 2D IoU >= 0.5 and prints, for labels within max_distance, the median relative error of the lifted
// centre's ground distance (boxes the lifter flags uncertain are counted apart), plus recall.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "beslam/detector_image/image_detector.hpp"
#include "beslam/formats/kitti_calib.hpp"
#include "beslam/formats/labels.hpp"

namespace fs = std::filesystem;
namespace formats = beslam::formats;
using namespace beslam::detector_image;

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr,
                 "usage: detector_image_eval <sequence folder> <tracking labels.txt> <model> [weights] "
                 "[max_distance_m=20] [camera_height=1.65] [score_threshold=0.3]\n");
    return 2;
  }
  try {
    const std::string folder = argv[1], labels_path = argv[2];
    DnnOptions dnn;
    dnn.model = argv[3];
    dnn.weights = argc > 4 ? argv[4] : "";
    const double max_distance = argc > 5 ? std::stod(argv[5]) : 20.0;
    LiftOptions lift;
    lift.camera_height = argc > 6 ? std::stod(argv[6]) : 1.65;
    if (argc > 7) dnn.score_threshold = std::stod(argv[7]);
    const std::string image_dir = fs::is_directory(folder + "/image_2") ? folder + "/image_2" : folder + "/image_0";
    const auto entries = formats::readCalibEntries(folder + "/calib.txt", {"P0", "P1", "P2", "P3", "Tr"});
    const auto p = entries.count("P2") && image_dir.back() == '2' ? entries.at("P2") : entries.at("P0");
    formats::Matrix34d P;
    for (int i = 0; i < 12; ++i) P(i / 4, i % 4) = p.values.at(static_cast<size_t>(i));
    std::vector<fs::path> images;
    for (const auto& e : fs::directory_iterator(image_dir)) images.push_back(e.path());
    std::sort(images.begin(), images.end());
    if (images.empty()) throw std::runtime_error(image_dir + ": no images");
    const cv::Mat first = cv::imread(images.front().string(), cv::IMREAD_COLOR);
    const formats::Camera c = formats::cameraFromProjection(P, first.cols, first.rows, "P");
    Detector2D detector(dnn);
    const GroundLifter lifter({sizeof(beslam_camera), c.width, c.height, 0, c.fx, c.fy, c.cx, c.cy}, lift);
    std::map<int64_t, std::vector<formats::ObjectLabel>> labels;
    for (const formats::TrackingLabel& l : formats::readTrackingLabels(labels_path))
      if (l.object.type == "Car") labels[l.frame].push_back(l.object);
    std::vector<double> errors;
    int truth = 0, found = 0, flagged_matches = 0;
    for (const fs::path& path : images) {
      const int64_t frame = std::stoll(path.stem().string());
      const cv::Mat image = cv::imread(path.string(), cv::IMREAD_COLOR);
      std::vector<beslam_box3d> boxes;
      std::vector<cv::Rect2d> rects;
      for (const Detection2D& d : detector.detect(image))
        if (d.class_id == BESLAM_CLASS_CAR) boxes.push_back(lifter.lift(d)), rects.push_back(d.box);
      std::vector<bool> used(boxes.size(), false);
      for (const formats::ObjectLabel& l : labels[frame]) {
        const double distance = std::hypot(l.p_cam_bottom.x(), l.p_cam_bottom.z());
        if (distance > max_distance) continue;
        ++truth;
        const cv::Rect2d r(l.x1, l.y1, l.x2 - l.x1, l.y2 - l.y1);
        int best = -1;
        double best_iou = 0.5;
        for (size_t k = 0; k < boxes.size(); ++k) {
          const double iou = (r & rects[k]).area() / (r | rects[k]).area();
          if (!used[k] && iou >= best_iou) best_iou = iou, best = static_cast<int>(k);
        }
        if (best < 0) continue;
        used[static_cast<size_t>(best)] = true;
        ++found;
        const beslam_box3d& b = boxes[static_cast<size_t>(best)];
        if (b.flags & BESLAM_BOX_UNCERTAIN) {
          ++flagged_matches;
          continue;
        }
        errors.push_back(std::abs(std::hypot(b.center_cam[0], b.center_cam[2]) - distance) / distance);
      }
    }
    std::sort(errors.begin(), errors.end());
    const double median = errors.empty() ? NAN : errors[errors.size() / 2];
    const double p90 = errors.empty() ? NAN : errors[errors.size() * 9 / 10];
    std::printf(
        "%zu frames: %d/%d cars within %.0f m detected (2D IoU >= 0.5), %d of them flagged uncertain; "
        "unflagged: median relative distance error %.1f %%, 90th percentile %.1f %% (%zu boxes)\n",
        images.size(), found, truth, max_distance, flagged_matches, 100 * median, 100 * p90, errors.size());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "detector_image_eval: %s\n", e.what());
    return 1;
  }
}
