// mask_bench: scores label masks against a synthetic sequence's ground truth (the `beslam bench masks`
// equivalent), and can generate a variant's masks in-process from the sequence's own labels.
//
//   mask_bench score    --masks RUN/masks --sequence OUT/sequences/00 [filters] [--csv FILE]
//   mask_bench generate --sequence OUT/sequences/00 --out DIR --variant V [--first N --last N] [filters]
//       V: box | box_contour | lidar_box | lidar_points | lidar_contour
//       Oracle boxes from label_02 (Car/Van/Pedestrian), motion from objects_motion.txt; writes
//       DIR/masks/NNNNNN.png exactly as a run with output.masks does, then scores them.
//       --perturb-m M --perturb-deg D: oracle boxes moved M metres (BEV) and turned +-D degrees first.
//       --overlay DIR: red = masked but not the object, blue = object but not masked.
//   filters: --max-distance 30 --max-occlusion 0 --max-truncation 0.1 --min-pixels 50
// Exit status: 0 ok, 1 input error (one line naming the file), 2 usage.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "beslam/formats/image_io.hpp"
#include "beslam/formats/kitti_calib.hpp"
#include "beslam/formats/labels.hpp"
#include "beslam/formats/velodyne.hpp"
#include "beslam/mask_common/mask_builder.hpp"
#include "beslam/mask_common/score.hpp"
#include "beslam/sdk/cli_args.hpp"
#include "beslam/sdk/detector.hpp"

namespace fs = std::filesystem;
using namespace beslam;

namespace {

struct Usage : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const char* kUsage =
    "usage: mask_bench score --masks DIR --sequence DIR [filters] [--csv FILE]\n"
    "       mask_bench generate --sequence DIR --out DIR --variant "
    "box|box_contour|lidar_box|lidar_points|lidar_contour\n"
    "                           [--first N] [--last N] [--overlay DIR] [--perturb-m M] [--perturb-deg D]\n"
    "                           [filters] [--csv FILE]\n"
    "filters: --max-distance M (30) --max-occlusion N (0) --max-truncation F (0.1) --min-pixels N (50)\n";

std::string frameName(int64_t frame) {
  std::string s = std::to_string(frame);
  return std::string(s.size() < 6 ? 6 - s.size() : 0, '0') + s;
}

int32_t classOf(const std::string& type) {
  if (type == "Car") return BESLAM_CLASS_CAR;
  if (type == "Van") return BESLAM_CLASS_VAN;
  if (type == "Truck") return BESLAM_CLASS_TRUCK;
  if (type == "Pedestrian") return BESLAM_CLASS_PEDESTRIAN;
  if (type == "Cyclist") return BESLAM_CLASS_CYCLIST;
  return BESLAM_CLASS_UNKNOWN;
}

void printSummary(const mask::ScoreSummary& s, const std::string& csv) {
  std::cout << std::fixed << std::setprecision(4) << "frames: " << s.frames << "\nobjects: " << s.objects.size()
            << "\nmedian IoU: " << s.median_iou << "\nmean IoU: " << s.mean_iou
            << "\n10th percentile IoU: " << s.p10_iou << "\nlabels right (dynamic/static): " << s.label_correct << "/"
            << s.label_checked << "\n";
  if (!csv.empty()) {
    std::ofstream out(csv);
    if (!out) throw std::runtime_error(csv + ": cannot write");
    out << "frame,track_id,distance,moving,predicted_label,gt_pixels,iou\n";
    for (const auto& o : s.objects)
      out << o.frame << ',' << o.track_id << ',' << o.distance << ',' << (o.moving ? 1 : 0) << ',' << o.predicted_label
          << ',' << o.gt_pixels << ',' << o.iou << '\n';
  }
}

// The `--key value` (or `--key=value`) options after the command, with number and required-key lookups.
struct CommandOptions {
  std::map<std::string, std::string> opt;

  double num(const std::string& k, double def) {
    if (!opt.count(k)) return def;
    try {
      size_t used = 0;
      const double v = std::stod(opt[k], &used);
      if (used != opt[k].size()) throw std::invalid_argument(k);
      return v;
    } catch (const std::exception&) {
      throw Usage("--" + k + ": '" + opt[k] + "' is not a number");
    }
  }
  std::string need(const std::string& k) {
    if (!opt.count(k)) throw Usage("--" + k + " is required");
    return opt[k];
  }
};

// Parses the options after the command, refusing unknown keys and options without a value.
CommandOptions parseOptions(const std::vector<std::string>& args) {
  std::map<std::string, std::string> opt;
  for (size_t i = 1; i < args.size(); ++i) {
    std::string a = args[i];
    if (a.rfind("--", 0) != 0) throw Usage("unexpected argument '" + a + "'");
    const auto eq = a.find('=');
    if (eq != std::string::npos) {
      opt[a.substr(2, eq - 2)] = a.substr(eq + 1);
    } else {
      if (i + 1 >= args.size()) throw Usage(a + " needs a value");
      opt[a.substr(2)] = args[++i];
    }
  }
  static const std::vector<std::string> known = {
      "masks", "sequence", "out", "variant",      "overlay",       "perturb-m",      "perturb-deg",
      "first", "last",     "csv", "max-distance", "max-occlusion", "max-truncation", "min-pixels"};
  for (const auto& [k, v] : opt)
    if (std::find(known.begin(), known.end(), k) == known.end()) throw Usage("unknown option --" + k);
  return {opt};
}

// The mask options of a `generate` variant.
mask::MaskOptions variantOptions(const std::string& variant) {
  mask::MaskOptions mo;
  if (variant == "box") {
    mo.contour = false;
  } else if (variant == "box_contour") {
    mo.contour = true;
  } else if (variant == "lidar_box") {
    mo.use_lidar = true, mo.point_masks = false, mo.contour = false;
  } else if (variant == "lidar_points") {
    mo.use_lidar = true, mo.contour = false;
  } else if (variant == "lidar_contour") {
    mo.use_lidar = true, mo.contour = true;
  } else {
    throw Usage("unknown --variant '" + variant + "'");
  }
  return mo;
}

// Oracle boxes of one frame from its labels and motion flags (DontCare skipped), moved and turned like a
// detector's error when perturb_m or perturb_deg is set.
std::vector<beslam_box3d> oracleBoxes(const std::vector<formats::TrackingLabel>& frame_labels,
                                      const std::map<std::pair<int64_t, int64_t>, bool>& moving, int64_t frame,
                                      double perturb_m, double perturb_deg) {
  std::vector<beslam_box3d> boxes;
  for (const auto& l : frame_labels) {
    if (l.object.isDontCare()) continue;
    beslam_box3d b = sdk::newBox();
    b.class_id = classOf(l.object.type);
    b.track_id = static_cast<int32_t>(l.track_id);
    const auto it = moving.find({frame, l.track_id});
    b.motion_state =
        it == moving.end() ? BESLAM_MOTION_UNKNOWN : (it->second ? BESLAM_MOTION_DYNAMIC : BESLAM_MOTION_STATIC);
    b.center_cam[0] = l.object.p_cam_bottom.x();
    b.center_cam[1] = l.object.p_cam_bottom.y() - l.object.h / 2;
    b.center_cam[2] = l.object.p_cam_bottom.z();
    b.size[0] = l.object.l, b.size[1] = l.object.w, b.size[2] = l.object.h;
    b.yaw = l.object.ry;
    b.score = 1;
    if (perturb_m > 0 || perturb_deg > 0) {
      // A detector's error, deterministic per (frame, track): perturb_m in a BEV direction, +-perturb_deg.
      const uint32_t h = static_cast<uint32_t>(frame * 2654435761u) ^ static_cast<uint32_t>(l.track_id * 40503u);
      const double a = (h % 360) * M_PI / 180;
      b.center_cam[0] += perturb_m * std::cos(a);
      b.center_cam[2] += perturb_m * std::sin(a);
      b.yaw += ((h >> 9) % 2 ? perturb_deg : -perturb_deg) * M_PI / 180;
    }
    boxes.push_back(b);
  }
  return boxes;
}

// Red: predicted, not the object; blue: object, not predicted; over the grey frame, into DIR/NNNNNN.png.
void writeOverlay(const fs::path& seq, int64_t frame, const cv::Mat& gray, const cv::Mat& mask,
                  const std::string& dir) {
  const cv::Mat inst = cv::imread((seq / "instance" / (frameName(frame) + ".png")).string(), cv::IMREAD_UNCHANGED);
  cv::Mat vis;
  cv::cvtColor(gray, vis, cv::COLOR_GRAY2BGR);
  if (inst.size() == mask.size() && inst.type() == CV_16UC1) {
    vis.setTo(cv::Scalar(0, 0, 255), (mask > 0) & (inst == 0));
    vis.setTo(cv::Scalar(255, 0, 0), (mask == 0) & (inst > 0));
  }
  fs::create_directories(dir);
  cv::imwrite((fs::path(dir) / (frameName(frame) + ".png")).string(), vis);
}

// The frames' images of the sequence (image_0, else image_2), sorted; cam_index gets the camera's index.
std::vector<fs::path> sequenceImages(const fs::path& seq, int& cam_index) {
  fs::path image_dir = seq / "image_0";
  if (!fs::is_directory(image_dir)) image_dir = seq / "image_2";
  cam_index = image_dir.filename() == "image_0" ? 0 : 2;
  std::vector<fs::path> images;
  for (const auto& e : fs::directory_iterator(image_dir))
    if (e.path().extension() == ".png") images.push_back(e.path());
  std::sort(images.begin(), images.end());
  if (images.empty()) throw std::runtime_error(image_dir.string() + ": no images");
  return images;
}

// `generate`: a variant's masks from the sequence's own labels into OUT/masks, timed, then scored.
int generate(CommandOptions& o, const mask::ScoreOptions& so, const std::string& csv, const std::string& sequence) {
  std::map<std::string, std::string>& opt = o.opt;
  const std::string variant = o.need("variant");
  const mask::MaskOptions mo = variantOptions(variant);
  const fs::path seq(sequence);
  const formats::KittiCalib calib = formats::readObjectCalib((seq / "calib.txt").string());
  if (!calib.P[0]) throw std::runtime_error((seq / "calib.txt").string() + ": no P0");
  int cam_index = 0;
  const std::vector<fs::path> images = sequenceImages(seq, cam_index);
  const cv::Size size = formats::readImageSize(images.front().string());
  const formats::Camera cam = formats::cameraFromProjection(*calib.P[cam_index], size.width, size.height, "P");
  mask::Intrinsics K;
  K.fx = cam.fx, K.fy = cam.fy, K.cx = cam.cx, K.cy = cam.cy, K.width = cam.width, K.height = cam.height;
  const std::optional<Eigen::Isometry3d> T = formats::T_cami_velo(calib, cam_index);
  if (mo.use_lidar && !T)
    throw std::runtime_error((seq / "calib.txt").string() + ": no Tr_velo_to_cam for a LiDAR variant");
  const mask::MaskBuilder builder(K, T, mo);

  std::string label_file;
  for (const auto& e : fs::directory_iterator(seq / "label_02"))
    if (e.path().extension() == ".txt") label_file = e.path().string();
  if (label_file.empty()) throw std::runtime_error((seq / "label_02").string() + ": no label file");
  std::map<int64_t, std::vector<formats::TrackingLabel>> labels;
  for (auto& l : formats::readTrackingLabels(label_file)) labels[l.frame].push_back(std::move(l));
  const auto moving = mask::readObjectMotionIfPresent((seq / "objects_motion.txt").string());

  const double perturb_m = o.num("perturb-m", 0), perturb_deg = o.num("perturb-deg", 0);
  const fs::path out_masks = fs::path(o.need("out")) / "masks";
  fs::create_directories(out_masks);
  std::vector<double> ms;
  for (const fs::path& image : images) {
    const int64_t frame = std::stoll(image.stem().string());
    if (frame < so.first || (so.last >= 0 && frame > so.last)) continue;
    const formats::LoadedImage img = formats::loadImage(image.string(), false);
    std::vector<float> scan;
    const fs::path scan_path = seq / "velodyne" / (frameName(frame) + ".bin");
    if (mo.use_lidar && fs::exists(scan_path)) scan = formats::readVelodyneBin(scan_path.string());
    const std::vector<beslam_box3d> boxes = oracleBoxes(labels[frame], moving, frame, perturb_m, perturb_deg);
    beslam_point_cloud_view view{};
    if (!scan.empty()) view.data = scan.data(), view.count = scan.size() / 4, view.stride_bytes = 16;
    cv::Mat mask = cv::Mat::zeros(img.gray.size(), CV_16UC1);
    const auto t0 = std::chrono::steady_clock::now();
    builder.generate(img.gray, view, boxes, mask);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (opt.count("overlay")) writeOverlay(seq, frame, img.gray, mask, opt["overlay"]);
    if (!cv::imwrite((out_masks / (frameName(frame) + ".png")).string(), mask))
      throw std::runtime_error((out_masks / (frameName(frame) + ".png")).string() + ": cannot write");
  }
  std::sort(ms.begin(), ms.end());
  std::cout << "variant: " << variant << "\nmask ms/frame (median): " << std::setprecision(3)
            << (ms.empty() ? 0 : ms[ms.size() / 2]) << "\n";
  printSummary(mask::scoreSequence(out_masks.string(), sequence, so), csv);
  return 0;
}

int run(const std::vector<std::string>& args) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  CommandOptions o = parseOptions(args);
  mask::ScoreOptions so;
  so.max_distance = o.num("max-distance", so.max_distance);
  so.max_occlusion = static_cast<int>(o.num("max-occlusion", so.max_occlusion));
  so.max_truncation = o.num("max-truncation", so.max_truncation);
  so.min_pixels = static_cast<int>(o.num("min-pixels", so.min_pixels));
  so.first = static_cast<int64_t>(o.num("first", 0));
  so.last = static_cast<int64_t>(o.num("last", -1));
  const std::string csv = o.opt.count("csv") ? o.opt["csv"] : "";
  const std::string sequence = o.need("sequence");

  if (command == "score") {
    printSummary(mask::scoreSequence(o.need("masks"), sequence, so), csv);
    return 0;
  }
  if (command != "generate") throw Usage("unknown command '" + command + "'");
  return generate(o, so, csv, sequence);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  return beslam::cli::runMain<Usage>([&] { return run(args); }, std::cerr, kUsage, "mask_bench: ", "mask_bench: ");
}
