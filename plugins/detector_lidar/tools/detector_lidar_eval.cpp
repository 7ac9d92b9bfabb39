// detector_lidar_eval: scores the LiDAR detector against KITTI labels.
//
//   detector_lidar_eval object   <kitti/object/training> <index> [match_m] [key=value...]
//   detector_lidar_eval sequence <sequence folder> <tracking labels.txt> [max_distance_m] [match_m] [key=value...]
//   detector_lidar_eval streets  <first seed> <count> [max_distance_m] [match_m] [key=value...]
//
// key=value sets a detector option: car_size=4.6,1.8,1.5 ground_method=grid box_fit=min_area
// lshape_min_points=N cluster_tolerance=X fov_context=X free_space=true|false free_space_min_rays=N.
//
// `sequence` reads a KITTI-odometry-layout folder (velodyne/NNNNNN.bin, calib.txt with P0/P2, R0_rect or
// R_rect, Tr_velo_to_cam or Tr) and KITTI tracking labels (label_02 rows; `beslam synth` writes this
// layout). It prints per-frame and total recall of Car labels within max_distance (BEV centre error below
// match_m, default 0.5), the median BEV error, and the false positives (detections > 2 m from any label).
// `streets` scores the tests' ray-cast streets (test/synthetic_scan.cpp, 8 cars a street; cars with at least 10
// points on them count). BESLAM_EVAL_VERBOSE=1 lists missed cars and unmatched detections.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "beslam/detector_lidar/lidar_detector.hpp"
#include "beslam/formats/image_io.hpp"
#include "beslam/formats/kitti_calib.hpp"
#include "beslam/formats/labels.hpp"
#include "beslam/formats/velodyne.hpp"
#include "box_match.hpp"
#include "synthetic_scan.hpp"

namespace fs = std::filesystem;
namespace formats = beslam::formats;
namespace eval = beslam::detector_lidar::eval;

namespace {

Eigen::Matrix3d rows3(const std::vector<double>& v) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = v[static_cast<size_t>(i)];
  return m;
}

struct Totals {
  int truth = 0, found = 0, detections = 0, false_positives = 0;
  std::vector<double> errors, milliseconds, cpu_milliseconds;
};

std::vector<beslam_box3d> timedDetect(const beslam::detector_lidar::LidarDetector& detector,
                                      const std::vector<float>& scan, Totals& totals) {
  auto cpu = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
  };
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = cpu();
  std::vector<beslam_box3d> boxes = detector.detect(scan.data(), scan.size() / 4);
  totals.cpu_milliseconds.push_back(cpu() - c0);
  totals.milliseconds.push_back(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  return boxes;
}

// Scan points (camera frame) inside a label's box grown by margin: how much of the car the sensor saw.
// With seen, the extent of those points along the box's length and width axes (relative to its centre).
int pointsInBox(const std::vector<Eigen::Vector3d>& p_cam, const beslam_box3d& b, double margin,
                std::array<double, 4>* seen = nullptr) {
  const double c = std::cos(b.yaw), s = std::sin(b.yaw);
  const Eigen::Vector2d heading(c, -s), side(s, c);  // (x, z) of the length and width axes
  int n = 0;
  std::array<double, 4> e = {1e9, -1e9, 1e9, -1e9};
  for (const Eigen::Vector3d& q : p_cam) {
    const Eigen::Vector2d d(q.x() - b.center_cam[0], q.z() - b.center_cam[2]);
    if (std::abs(d.dot(heading)) <= b.size[0] / 2 + margin && std::abs(d.dot(side)) <= b.size[1] / 2 + margin &&
        std::abs(q.y() - b.center_cam[1]) <= b.size[2] / 2 - 0.3) {  // above the ground's noise
      ++n;
      e[0] = std::min(e[0], d.dot(heading)), e[1] = std::max(e[1], d.dot(heading));
      e[2] = std::min(e[2], d.dot(side)), e[3] = std::max(e[3], d.dot(side));
    }
  }
  if (seen) *seen = e;
  return n;
}

void score(const std::vector<beslam_box3d>& truth_all, const std::vector<beslam_box3d>& detections, double max_distance,
           double match, Totals& totals, const std::string& name, const std::vector<Eigen::Vector3d>* p_cam = nullptr,
           const std::vector<beslam_box3d>* fp_truth = nullptr) {
  std::vector<beslam_box3d> truth;
  for (const beslam_box3d& t : truth_all)
    if (std::hypot(t.center_cam[0], t.center_cam[2]) <= max_distance) truth.push_back(t);
  int found = 0;
  const bool verbose = std::getenv("BESLAM_EVAL_VERBOSE") != nullptr;
  for (const eval::Match& m : eval::matchBev(truth, detections, match)) {
    const beslam_box3d& t = truth[m.truth];
    if (m.detection >= 0) {
      ++found, totals.errors.push_back(m.error);
      if (verbose && !p_cam)
        std::printf("  car at x %.2f z %.2f: BEV error %.2f m\n", t.center_cam[0], t.center_cam[2], m.error);
      continue;
    }
    if (!verbose) continue;
    std::array<double, 4> seen{};
    const int n = p_cam ? pointsInBox(*p_cam, t, 0.1, &seen) : -1;
    std::printf("  missed car at x %.2f z %.2f, %.2f x %.2f, yaw %.2f, %d points (length %.2f..%.2f, width %.2f..%.2f)",
                t.center_cam[0], t.center_cam[2], t.size[0], t.size[1], t.yaw, n, seen[0], seen[1], seen[2], seen[3]);
    double nearest = 1e9;
    int k = -1;
    for (size_t d = 0; d < detections.size(); ++d)
      if (eval::bevDistance(detections[d], t) < nearest)
        nearest = eval::bevDistance(detections[d], t), k = static_cast<int>(d);
    if (k >= 0 && nearest < 3) {
      const beslam_box3d& d = detections[static_cast<size_t>(k)];
      std::printf("; nearest box %.2f m off at x %.2f z %.2f, %.2f x %.2f, yaw %.2f", nearest, d.center_cam[0],
                  d.center_cam[2], d.size[0], d.size[1], d.yaw);
    }
    std::printf("\n");
  }
  int fp = 0;
  for (const beslam_box3d& d : detections) {
    double nearest = 1e9;
    for (const beslam_box3d& t : fp_truth ? *fp_truth : truth_all) nearest = std::min(nearest, eval::bevDistance(d, t));
    if (nearest > 2.0 && std::getenv("BESLAM_EVAL_VERBOSE") != nullptr)
      std::printf("  unmatched detection at x %.2f z %.2f, %.2f x %.2f x %.2f m, score %.2f\n", d.center_cam[0],
                  d.center_cam[2], d.size[0], d.size[1], d.size[2], d.score);
    fp += nearest > 2.0;
  }
  std::printf("%s: %d/%zu cars found, %zu detections, %d false positives\n", name.c_str(), found, truth.size(),
              detections.size(), fp);
  totals.truth += static_cast<int>(truth.size());
  totals.found += found;
  totals.detections += static_cast<int>(detections.size());
  totals.false_positives += fp;
}

void summary(Totals& t, double max_distance, double match) {
  std::sort(t.errors.begin(), t.errors.end());
  const double median = t.errors.empty() ? NAN : t.errors[t.errors.size() / 2];
  std::sort(t.milliseconds.begin(), t.milliseconds.end());
  const double ms = t.milliseconds.empty() ? NAN : t.milliseconds[t.milliseconds.size() / 2];
  std::sort(t.cpu_milliseconds.begin(), t.cpu_milliseconds.end());
  const double cpu_ms = t.cpu_milliseconds.empty() ? NAN : t.cpu_milliseconds[t.cpu_milliseconds.size() / 2];
  std::printf(
      "total: recall %.3f (%d/%d cars within %.0f m found within %.2f m), median BEV error %.3f m, "
      "%d detections, %d false positives, median %.1f ms per scan (%.1f ms CPU, all threads)\n",
      t.truth ? static_cast<double>(t.found) / t.truth : 0.0, t.found, t.truth, max_distance, match, median,
      t.detections, t.false_positives, ms, cpu_ms);
}

// Applies trailing key=value arguments to the options; returns the number of positional arguments.
int applyOptions(int argc, char** argv, beslam::detector_lidar::Options& o) {
  int positional = argc;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    const size_t eq = arg.find('=');
    if (eq == std::string::npos) continue;
    positional = std::min(positional, i);
    const std::string key = arg.substr(0, eq), value = arg.substr(eq + 1);
    if (key == "car_size") {
      std::vector<double> v;
      size_t start = 0;
      for (size_t comma; (comma = value.find(',', start)) != std::string::npos; start = comma + 1)
        v.push_back(std::stod(value.substr(start, comma - start)));
      v.push_back(std::stod(value.substr(start)));
      if (v.size() != 3) throw std::invalid_argument("car_size needs three numbers");
      o.car_size = {v[0], v[1], v[2]};
    } else if (key == "ground_method") {
      o.ground_method = value;
    } else if (key == "box_fit") {
      o.box_fit = value;
    } else if (key == "lshape_min_points") {
      o.lshape_min_points = std::stoi(value);
    } else if (key == "cluster_tolerance") {
      o.cluster_tolerance = std::stod(value);
    } else if (key == "fov_context") {
      o.fov_context = std::stod(value);
    } else if (key == "free_space") {
      o.free_space = value == "true" || value == "1";
    } else if (key == "free_space_min_rays") {
      o.free_space_min_rays = std::stoi(value);
    } else {
      throw std::invalid_argument("unknown option '" + key + "'");
    }
  }
  o.validate();
  return positional;
}

int usage() {
  std::fprintf(stderr,
               "usage: detector_lidar_eval object <kitti/object/training> <index> [match_m] [key=value...]\n"
               "       detector_lidar_eval sequence <folder> <tracking_labels.txt> [max_distance_m] [match_m] "
               "[key=value...]\n"
               "       detector_lidar_eval streets <first_seed> <count> [max_distance_m] [match_m] [key=value...]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) return usage();
  const std::string mode = argv[1];
  try {
    beslam::detector_lidar::Options options;
    argc = applyOptions(argc, argv, options);
    if (mode == "object") {
      const std::string root = argv[2], index = argv[3];
      const double match = argc > 4 ? std::stod(argv[4]) : 0.5;
      const formats::KittiCalib calib = formats::readObjectCalib(root + "/calib/" + index + ".txt");
      const cv::Size size = formats::readImageSize(root + "/image_2/" + index + ".png");
      const formats::Camera c = formats::cameraFromProjection(*calib.P[2], size.width, size.height, "P2");
      const beslam::detector_lidar::LidarDetector detector(
          options, *formats::T_cami_velo(calib, 2),
          beslam_camera{sizeof(beslam_camera), c.width, c.height, 0, c.fx, c.fy, c.cx, c.cy});
      const std::vector<float> scan = formats::readVelodyneBin(root + "/velodyne/" + index + ".bin");
      std::vector<beslam_box3d> truth;
      for (const formats::ObjectLabel& l : formats::readObjectLabels(root + "/label_2/" + index + ".txt"))
        if (l.type == "Car") truth.push_back(eval::labelToBox(l, BESLAM_CLASS_CAR));
      Totals totals;
      for (int warm = 0; warm < 4; ++warm) timedDetect(detector, scan, totals);  // timing: one frame, five runs
      score(truth, timedDetect(detector, scan, totals), 1e9, match, totals, index);
      summary(totals, 1e9, match);
      return 0;
    }
    if (mode == "streets") {
      // The test's ray-caster (test/synthetic_scan.cpp): cars with >= 10 points within max_distance count.
      const int first = std::stoi(argv[2]), count = std::stoi(argv[3]);
      const double max_distance = argc > 4 ? std::stod(argv[4]) : 30.0;
      const double match = argc > 5 ? std::stod(argv[5]) : 0.5;
      namespace synth = beslam::detector_lidar::synth;
      const Eigen::Isometry3d T = synth::kittiLikeTcamLidar();
      const beslam::detector_lidar::LidarDetector detector(options, T, synth::kittiLikeCamera());
      Totals totals;
      for (int seed = first; seed < first + count; ++seed) {
        const synth::Scene scene = synth::randomScene(static_cast<uint32_t>(seed), 8, max_distance);
        const synth::Scan scan = synth::castScan(scene, static_cast<uint32_t>(seed));
        const std::vector<beslam_box3d> truth_all = synth::truthBoxes(scene, T);
        std::vector<beslam_box3d> truth;
        size_t car = 0;
        for (size_t k = 0; k < scene.objects.size(); ++k) {
          if (!scene.objects[k].is_car) continue;
          const beslam_box3d& b = truth_all[car++];
          if (scan.hits_per_object[k] >= 10) truth.push_back(b);
        }
        std::vector<Eigen::Vector3d> p_cam;
        for (size_t i = 0; i + 3 < scan.xyzi.size(); i += 4)
          p_cam.push_back(T * Eigen::Vector3d(scan.xyzi[i], scan.xyzi[i + 1], scan.xyzi[i + 2]));
        // False positives are scored against every car, the hidden ones included.
        const std::vector<beslam_box3d> detections = timedDetect(detector, scan.xyzi, totals);
        score(truth, detections, max_distance, match, totals, "seed " + std::to_string(seed), &p_cam, &truth_all);
      }
      summary(totals, max_distance, match);
      return 0;
    }
    if (mode == "sequence") {
      const std::string folder = argv[2], labels = argv[3];
      const double max_distance = argc > 4 ? std::stod(argv[4]) : 30.0;
      const double match = argc > 5 ? std::stod(argv[5]) : 0.5;
      const auto entries = formats::readCalibEntries(folder + "/calib.txt", {"P0", "P1", "P2", "P3", "Tr"});
      auto find = [&](std::initializer_list<const char*> names) -> const formats::CalibEntry* {
        for (const char* n : names) {
          auto it = entries.find(n);
          if (it != entries.end()) return &it->second;
        }
        return nullptr;
      };
      const formats::CalibEntry* tr = find({"Tr_velo_to_cam", "Tr_velo_cam", "Tr"});
      const formats::CalibEntry* p = find({"P2", "P0"});
      if (tr == nullptr || tr->values.size() != 12 || p == nullptr || p->values.size() != 12) {
        std::fprintf(stderr, "%s/calib.txt: needs Tr_velo_to_cam (or Tr) and P2 (or P0) with 12 values\n",
                     folder.c_str());
        return 1;
      }
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      for (int i = 0; i < 12; ++i) T.matrix()(i / 4, i % 4) = tr->values[static_cast<size_t>(i)];
      if (const formats::CalibEntry* r0 = find({"R0_rect", "R_rect"}); r0 != nullptr && r0->values.size() == 9) {
        Eigen::Isometry3d R = Eigen::Isometry3d::Identity();
        R.linear() = rows3(r0->values);
        T = R * T;
      }
      formats::Matrix34d P;
      for (int i = 0; i < 12; ++i) P(i / 4, i % 4) = p->values[static_cast<size_t>(i)];
      T = formats::T_cami_rect0(P) * T;
      std::optional<beslam_camera> camera;
      for (const char* dir : {"image_2", "image_0"}) {
        if (!fs::is_directory(folder + "/" + dir)) continue;
        std::vector<fs::path> images;
        for (const auto& e : fs::directory_iterator(folder + "/" + dir)) images.push_back(e.path());
        if (images.empty()) continue;
        const cv::Size size = formats::readImageSize(std::min_element(images.begin(), images.end())->string());
        const formats::Camera c = formats::cameraFromProjection(P, size.width, size.height, "P");
        camera = beslam_camera{sizeof(beslam_camera), c.width, c.height, 0, c.fx, c.fy, c.cx, c.cy};
        break;
      }
      const beslam::detector_lidar::LidarDetector detector(options, T, camera);
      std::map<int64_t, std::vector<beslam_box3d>> truth;
      for (const formats::TrackingLabel& l : formats::readTrackingLabels(labels))
        if (l.object.type == "Car") truth[l.frame].push_back(eval::labelToBox(l.object, BESLAM_CLASS_CAR));
      std::vector<fs::path> scans;
      for (const auto& e : fs::directory_iterator(folder + "/velodyne"))
        if (e.path().extension() == ".bin") scans.push_back(e.path());
      std::sort(scans.begin(), scans.end());
      Totals totals;
      for (const fs::path& s : scans) {
        const int64_t frame = std::stoll(s.stem().string());
        const std::vector<float> scan = formats::readVelodyneBin(s.string());
        std::vector<Eigen::Vector3d> p_cam;
        if (std::getenv("BESLAM_EVAL_VERBOSE") != nullptr)
          for (size_t i = 0; i + 3 < scan.size(); i += 4)
            p_cam.push_back(T * Eigen::Vector3d(scan[i], scan[i + 1], scan[i + 2]));
        score(truth[frame], timedDetect(detector, scan, totals), max_distance, match, totals, s.stem().string(),
              &p_cam);
      }
      summary(totals, max_distance, match);
      return 0;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "detector_lidar_eval: %s\n", e.what());
    return 1;
  }
  return usage();
}
