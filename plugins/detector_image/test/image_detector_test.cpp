// detector_image: the real 2D detector on KITTI 06 frame 20, the ground lifting against synthetic ground
// truth, uncertainty flags, and malformed input (missing / unreadable model files) through the C ABI.
#include "beslam/detector_image/image_detector.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>

#include "beslam/formats/kitti_calib.hpp"
#include "beslam/formats/labels.hpp"
#include "beslam/sdk/views.hpp"
#include "beslam/test/abi_harness.hpp"

namespace fs = std::filesystem;
using namespace beslam::detector_image;

namespace {

const std::string kModelDir = std::string(BESLAM_SHARED_MODELS) + "/yolo-fastest-1.1";
const std::string kCfg = kModelDir + "/yolo-fastest-1.1.cfg";
const std::string kWeights = kModelDir + "/yolo-fastest-1.1.weights";
const std::string kSeq06 = std::string(BESLAM_SHARED_DATA) + "/kitti/odometry/sequences/06";

bool haveModel() { return fs::exists(kCfg) && fs::exists(kWeights); }
const std::string kYolox = std::string(BESLAM_SHARED_MODELS) + "/yolox-nano/yolox_nano.onnx";
bool haveYolox() { return fs::exists(kYolox); }
const std::string kObject = std::string(BESLAM_SHARED_DATA) + "/kitti/object/training";
bool haveObject() {
  return fs::exists(kObject + "/image_2/000008.png") && fs::exists(kObject + "/calib/000008.txt") &&
         fs::exists(kObject + "/label_2/000008.txt");
}
bool haveSeq06() { return fs::exists(kSeq06 + "/image_0/000020.png") && fs::exists(kSeq06 + "/calib.txt"); }

beslam_camera seq06Camera(const cv::Mat& image) {
  const beslam::formats::KittiCalib calib = beslam::formats::readOdometryCalib(kSeq06 + "/calib.txt");
  const beslam::formats::Camera c = beslam::formats::cameraFromProjection(*calib.P[0], image.cols, image.rows, "P0");
  return {sizeof(beslam_camera), c.width, c.height, 0, c.fx, c.fy, c.cx, c.cy};
}

beslam_camera kittiCamera() { return {sizeof(beslam_camera), 1242, 375, 0, 721.5, 721.5, 609.6, 172.9}; }

// The 2D box of a ground-truth 3D box (camera frame), clipped to the image; false when behind the camera.
bool projectBox(const beslam_camera& cam, const beslam_box3d& box, cv::Rect2d& out) {
  const Eigen::Matrix<double, 3, 8> corners = beslam::sdk::boxCorners(box);
  double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
  for (int i = 0; i < 8; ++i) {
    if (corners(2, i) < 0.2) return false;
    const double u = cam.fx * corners(0, i) / corners(2, i) + cam.cx,
                 v = cam.fy * corners(1, i) / corners(2, i) + cam.cy;
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
  }
  u0 = std::max(u0, 0.0), v0 = std::max(v0, 0.0), u1 = std::min(u1, cam.width - 1.0),
  v1 = std::min(v1, cam.height - 1.0);
  if (u1 - u0 < 4 || v1 - v0 < 4) return false;
  out = cv::Rect2d(u0, v0, u1 - u0, v1 - v0);
  return true;
}

// The exact 2D box of a road-aligned prior-size car standing on the road at (x, z) of the KITTI camera.
cv::Rect2d roadCarBox(const beslam_camera& cam, double z, double x) {
  beslam_box3d t{};
  t.size[0] = 3.9, t.size[1] = 1.6, t.size[2] = 1.5, t.yaw = -1.5708;
  t.center_cam[0] = x, t.center_cam[1] = 1.65 - 0.75, t.center_cam[2] = z;
  cv::Rect2d r;
  EXPECT_TRUE(projectBox(cam, t, r));
  return r;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

}  // namespace

TEST(ImageDetector, Kitti06Frame20FindsTheParkedCarOnTheRight) {
  if (!haveModel()) GTEST_SKIP() << "Yolo-Fastest not found under " << kModelDir << " (shared models absent)";
  if (!haveSeq06()) GTEST_SKIP() << "KITTI odometry 06 not found under " << kSeq06 << " (shared data absent)";
  const cv::Mat image = cv::imread(kSeq06 + "/image_0/000020.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty());
  DnnOptions dnn;
  dnn.model = kCfg, dnn.weights = kWeights;
  Detector2D detector(dnn);
  const GroundLifter lifter(seq06Camera(image), LiftOptions{});
  bool found = false;
  for (const Detection2D& d : detector.detect(image)) {
    const beslam_box3d b = lifter.lift(d);
    const double distance = std::hypot(b.center_cam[0], b.center_cam[2]);
    std::printf(
        "class %d score %.2f box [%.0f %.0f %.0f %.0f] -> centre x %.2f y %.2f z %.2f (ground distance %.2f m), "
        "yaw %.2f%s\n",
        d.class_id, d.score, d.box.x, d.box.y, d.box.x + d.box.width, d.box.y + d.box.height, b.center_cam[0],
        b.center_cam[1], b.center_cam[2], distance, b.yaw, (b.flags & BESLAM_BOX_UNCERTAIN) ? " uncertain" : "");
    EXPECT_TRUE(b.flags & BESLAM_BOX_HAS_BBOX2D);
    const double u = d.box.x + d.box.width / 2;
    if (d.class_id == BESLAM_CLASS_CAR && u > image.cols / 2.0 && b.center_cam[2] > 12 && b.center_cam[2] < 19 &&
        b.center_cam[0] > 0 && !(b.flags & BESLAM_BOX_UNCERTAIN))
      found = true;
  }
  EXPECT_TRUE(found) << "no certain car right of centre 12-19 m ahead";
}

// The colour frame of KITTI object 000008 against its six car labels: boxes the lifter does not flag are
// matched to labels by 2D IoU and their centre's ground distance compared with the label's.
TEST(ImageDetector, Kitti000008LiftedDistancesAgainstLabels) {
  if (!haveModel()) GTEST_SKIP() << "Yolo-Fastest not found under " << kModelDir << " (shared models absent)";
  if (!haveObject()) GTEST_SKIP() << "KITTI object 000008 not found under " << kObject << " (shared data absent)";
  const cv::Mat image = cv::imread(kObject + "/image_2/000008.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  const beslam::formats::KittiCalib calib = beslam::formats::readObjectCalib(kObject + "/calib/000008.txt");
  const beslam::formats::Camera c = beslam::formats::cameraFromProjection(*calib.P[2], image.cols, image.rows, "P2");
  DnnOptions dnn;
  dnn.model = kCfg, dnn.weights = kWeights;
  Detector2D detector(dnn);
  const GroundLifter lifter({sizeof(beslam_camera), c.width, c.height, 0, c.fx, c.fy, c.cx, c.cy}, LiftOptions{});
  const std::vector<beslam::formats::ObjectLabel> labels =
      beslam::formats::readObjectLabels(kObject + "/label_2/000008.txt");
  std::vector<double> errors;
  int flagged = 0, cars = 0;
  for (const Detection2D& d : detector.detect(image)) {
    if (d.class_id != BESLAM_CLASS_CAR) continue;
    ++cars;
    const beslam_box3d b = lifter.lift(d);
    if (b.flags & BESLAM_BOX_UNCERTAIN) {
      ++flagged;
      continue;
    }
    double best_iou = 0;
    const beslam::formats::ObjectLabel* match = nullptr;
    for (const auto& l : labels) {
      if (l.type != "Car") continue;
      const cv::Rect2d r(l.x1, l.y1, l.x2 - l.x1, l.y2 - l.y1);
      const double iou = (r & d.box).area() / (r | d.box).area();
      if (iou > best_iou) best_iou = iou, match = &l;
    }
    if (match == nullptr || best_iou < 0.4) continue;
    const double truth = std::hypot(match->p_cam_bottom.x(), match->p_cam_bottom.z());
    const double lifted = std::hypot(b.center_cam[0], b.center_cam[2]);
    std::printf("car at %.2f m (label), lifted %.2f m: error %+.1f %% (IoU %.2f)\n", truth, lifted,
                100 * (lifted - truth) / truth, best_iou);
    errors.push_back(std::abs(lifted - truth) / truth);
  }
  std::printf("%d car boxes, %d flagged uncertain, %zu certain ones matched: median distance error %.1f %%\n", cars,
              flagged, errors.size(), 100 * median(errors));
  ASSERT_GE(errors.size(), 3u);
  EXPECT_LT(median(errors), 0.10);
}

// Both shipped models on KITTI object 000008's colour frame against its six labelled cars: a label counts as
// found when a car box overlaps it with 2D IoU >= 0.5; for those, the bottom edge's error in pixels (what the
// flat-road range is lifted from). Labels cut by the image border (truncation > 0) have their bottom edge at
// the border and are left out of the edge error.
struct LabelScore {
  int labels = 0, found = 0;
  std::vector<double> bottom_errors;  // px, unclipped labels
};

LabelScore scoreOn000008(const DnnOptions& dnn) {
  const cv::Mat image = cv::imread(kObject + "/image_2/000008.png", cv::IMREAD_COLOR);
  Detector2D detector(dnn);
  const std::vector<Detection2D> detections = detector.detect(image);
  LabelScore score;
  for (const auto& l : beslam::formats::readObjectLabels(kObject + "/label_2/000008.txt")) {
    if (l.type != "Car") continue;
    ++score.labels;
    const cv::Rect2d r(l.x1, l.y1, l.x2 - l.x1, l.y2 - l.y1);
    double best_iou = 0;
    const Detection2D* match = nullptr;
    for (const Detection2D& d : detections) {
      if (d.class_id != BESLAM_CLASS_CAR) continue;
      const double iou = (r & d.box).area() / (r | d.box).area();
      if (iou > best_iou) best_iou = iou, match = &d;
    }
    if (match == nullptr || best_iou < 0.5) continue;
    ++score.found;
    if (l.truncated <= 0) score.bottom_errors.push_back(match->box.y + match->box.height - l.y2);
  }
  return score;
}

TEST(ImageDetector, YoloxNanoAgainstYoloFastestOn000008) {
  if (!haveModel() || !haveYolox()) GTEST_SKIP() << "shared models absent under " << BESLAM_SHARED_MODELS;
  if (!haveObject()) GTEST_SKIP() << "KITTI object 000008 not found under " << kObject << " (shared data absent)";
  DnnOptions fastest;
  fastest.model = kCfg, fastest.weights = kWeights;
  DnnOptions yolox;
  yolox.model = kYolox, yolox.input_width = 416, yolox.input_height = 416;
  const LabelScore a = scoreOn000008(fastest), b = scoreOn000008(yolox);
  auto absMedian = [](std::vector<double> v) {
    for (double& x : v) x = std::abs(x);
    return median(v);
  };
  std::printf("Yolo-Fastest 320: %d of %d labelled cars found, bottom edge |error| median %.1f px over %zu\n", a.found,
              a.labels, absMedian(a.bottom_errors), a.bottom_errors.size());
  std::printf("YOLOX-Nano 416:   %d of %d labelled cars found, bottom edge |error| median %.1f px over %zu\n", b.found,
              b.labels, absMedian(b.bottom_errors), b.bottom_errors.size());
  EXPECT_EQ(a.labels, 6);
  EXPECT_GE(b.found, a.found);
  ASSERT_GE(b.bottom_errors.size(), 2u);
  EXPECT_LT(absMedian(b.bottom_errors), 6.0);
}

TEST(ImageDetector, HeadAutoTellsYoloxFromDarknetAtAnyInputSize) {
  if (!haveModel() || !haveYolox()) GTEST_SKIP() << "shared models absent under " << BESLAM_SHARED_MODELS;
  DnnOptions yolox;
  yolox.model = kYolox, yolox.input_width = 416, yolox.input_height = 416;
  EXPECT_EQ(Detector2D(yolox).head(), "yolox");
  // A wide input that fits KITTI's aspect: the grid head follows the input's size.
  yolox.input_width = 832, yolox.input_height = 256;
  EXPECT_EQ(Detector2D(yolox).head(), "yolox");
  DnnOptions fastest;
  fastest.model = kCfg, fastest.weights = kWeights;
  EXPECT_EQ(Detector2D(fastest).head(), "yolo");
  fastest.head = "yolox";
  EXPECT_THROW(Detector2D{fastest}, std::invalid_argument);  // yolox needs an ONNX model
  yolox.head = "ssd";
  EXPECT_THROW(Detector2D{yolox}, std::invalid_argument);
}

// Cars within 20 m (sizes +-10 % around the prior), their exact 2D boxes with noise on every edge (1 px, or
// a detector-like 4 % of the box size): the lifted centre's distance against the true one.
TEST(GroundLifter, SyntheticCarsWithin20mMedianDistanceErrorUnder10Percent) {
  struct Case {
    double pitch, relative_noise;
  };
  for (const Case& k : {Case{0.0, 0.0}, Case{0.03, 0.0}, Case{0.0, 0.04}}) {
    const double pitch = k.pitch;
    const beslam_camera cam = kittiCamera();
    LiftOptions options;
    options.camera_pitch = pitch;
    const GroundLifter lifter(cam, options);
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> u01(0, 1);
    std::normal_distribution<double> px(0, 1.0);
    std::vector<double> errors;
    int uncertain = 0;
    const double c = std::cos(pitch), s = std::sin(pitch);
    while (errors.size() < 300) {
      // Ground truth in the level frame (camera 1.65 m above the road), then rotated into the pitched camera.
      const double z = 4 + 16 * u01(rng), x = (u01(rng) - 0.5) * 2 * std::min(8.0, 0.7 * z);
      if (std::hypot(x, z) > 20) continue;
      beslam_box3d truth{};
      truth.class_id = BESLAM_CLASS_CAR;
      truth.size[0] = 3.9 * (0.9 + 0.2 * u01(rng)), truth.size[1] = 1.6 * (0.92 + 0.16 * u01(rng));
      truth.size[2] = 1.5 * (0.9 + 0.2 * u01(rng));
      truth.yaw = u01(rng) < 0.7 ? -1.5708 + 0.2 * (u01(rng) - 0.5) + (u01(rng) < 0.5 ? 3.14159 : 0) : 6.283 * u01(rng);
      const Eigen::Vector3d level(x, 1.65 - truth.size[2] / 2, z);
      const Eigen::Vector3d cam_p(level.x(), c * level.y() - s * level.z(), s * level.y() + c * level.z());
      for (int k = 0; k < 3; ++k) truth.center_cam[k] = cam_p[k];
      // The pitched camera sees the box rotated too: project its corners through the same rotation.
      beslam_box3d level_box = truth;
      for (int k = 0; k < 3; ++k) level_box.center_cam[k] = level[k];
      Eigen::Matrix<double, 3, 8> corners = beslam::sdk::boxCorners(level_box);
      double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
      bool behind = false;
      for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3d q(corners(0, i), c * corners(1, i) - s * corners(2, i),
                                s * corners(1, i) + c * corners(2, i));
        if (q.z() < 0.2) behind = true;
        const double u = cam.fx * q.x() / q.z() + cam.cx, v = cam.fy * q.y() / q.z() + cam.cy;
        u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
      }
      if (behind) continue;
      const double nu = std::max(1.0, k.relative_noise * (u1 - u0)), nv = std::max(1.0, k.relative_noise * (v1 - v0));
      u0 = std::max(u0 + nu * px(rng), 0.0), v0 = std::max(v0 + nv * px(rng), 0.0);
      u1 = std::min(u1 + nu * px(rng), cam.width - 1.0), v1 = std::min(v1 + nv * px(rng), cam.height - 1.0);
      if (u1 - u0 < 4 || v1 - v0 < 4 || u0 <= 3 || u1 >= cam.width - 4 || v1 >= cam.height - 4) continue;  // cut boxes
      const beslam_box3d lifted = lifter.lift({BESLAM_CLASS_CAR, 0.9f, cv::Rect2d(u0, v0, u1 - u0, v1 - v0)});
      const double d_true = cam_p.norm();
      const double d_lift = Eigen::Vector3d(lifted.center_cam[0], lifted.center_cam[1], lifted.center_cam[2]).norm();
      errors.push_back(std::abs(d_lift - d_true) / d_true);
      uncertain += (lifted.flags & BESLAM_BOX_UNCERTAIN) != 0;
    }
    std::vector<double> sorted = errors;
    std::sort(sorted.begin(), sorted.end());
    std::printf(
        "pitch %.2f, edge noise %s: %zu cars within 20 m, median relative distance error %.3f, 90th "
        "percentile %.3f, %d flagged uncertain\n",
        pitch, k.relative_noise > 0 ? "4 % of the box" : "1 px", errors.size(), median(errors),
        sorted[sorted.size() * 9 / 10], uncertain);
    EXPECT_LT(median(errors), 0.10);
  }
}

TEST(GroundLifter, FlagsFarCutAndHorizonBoxes) {
  const beslam_camera cam = kittiCamera();
  const GroundLifter lifter(cam, LiftOptions{});
  auto boxAt = [&](double z, double x) { return roadCarBox(cam, z, x); };
  const beslam_box3d near = lifter.lift({BESLAM_CLASS_CAR, 0.8f, boxAt(10, 2)});
  EXPECT_FALSE(near.flags & BESLAM_BOX_UNCERTAIN);
  EXPECT_NEAR(near.center_cam[2], 10, 0.3);
  EXPECT_NEAR(near.center_cam[0], 2, 0.2);
  EXPECT_NEAR(near.center_cam[1], 0.9, 0.05);
  EXPECT_EQ(near.class_id, BESLAM_CLASS_CAR);
  EXPECT_EQ(near.track_id, -1);
  EXPECT_FLOAT_EQ(near.score, 0.8f);
  EXPECT_TRUE(lifter.lift({BESLAM_CLASS_CAR, 0.8f, boxAt(60, 2)}).flags & BESLAM_BOX_UNCERTAIN);  // far
  const beslam_box3d cut = lifter.lift({BESLAM_CLASS_CAR, 0.8f, cv::Rect2d(0, 150, 200, 150)});   // left border
  EXPECT_TRUE(cut.flags & BESLAM_BOX_UNCERTAIN);
  // Bottom edge above the horizon: the road is never there; the height prior places it, uncertain.
  const beslam_box3d sky = lifter.lift({BESLAM_CLASS_CAR, 0.8f, cv::Rect2d(600, 100, 60, 40)});
  EXPECT_TRUE(sky.flags & BESLAM_BOX_UNCERTAIN);
  EXPECT_TRUE(std::isfinite(sky.center_cam[2]) && sky.center_cam[2] > 0);
  const beslam_box3d ped = lifter.lift({BESLAM_CLASS_PEDESTRIAN, 0.7f, cv::Rect2d(700, 120, 40, 110)});
  EXPECT_DOUBLE_EQ(ped.size[2], 1.75);
  EXPECT_TRUE(std::isfinite(ped.center_cam[2]));
}

// ABI 1.5: every lifted box says how well its centre is known, along the line of sight and across it, and how
// its range error drifts with the range (the road pitch). The stated range noise matches the scatter that
// pixel noise on the box edges causes.
TEST(GroundLifter, BoxesCarryTheirRangeAndBearingNoise) {
  const beslam_camera cam = kittiCamera();
  auto boxAt = [&](double z, double x) { return roadCarBox(cam, z, x); };
  const GroundLifter lifter(cam, LiftOptions{});
  const beslam_box3d near = lifter.lift({BESLAM_CLASS_CAR, 0.8f, boxAt(10, 3)});
  const beslam_box3d far = lifter.lift({BESLAM_CLASS_CAR, 0.8f, boxAt(30, 3)});
  for (const beslam_box3d* b : {&near, &far}) {
    ASSERT_TRUE(b->flags & BESLAM_BOX_HAS_POSITION_SIGMA);
    EXPECT_GT(b->position_sigma[0], 2 * b->position_sigma[1]);  // range is the weak direction
  }
  // Range noise grows with the square of the range (of the bottom edge, the car's near end: (29/9)^2 = 10.4
  // from 10 to 30 m), bearing noise and the drift with the range.
  EXPECT_NEAR(far.position_sigma[0] / near.position_sigma[0], 10.4, 2.0);
  EXPECT_NEAR(far.position_sigma[1] / near.position_sigma[1], 3.0, 0.5);
  EXPECT_NEAR(far.range_drift / near.range_drift, 3.0, 0.5);
  EXPECT_NEAR(near.range_drift, 2 * 10 * 0.005 / 1.65, 0.01);  // 2 Z pitch_sigma / camera height
  // A box cut by the border: the centre is known to about half a car length.
  const beslam_box3d cut = lifter.lift({BESLAM_CLASS_CAR, 0.8f, cv::Rect2d(0, 150, 200, 150)});
  EXPECT_GE(cut.position_sigma[0], 3.9 / 2);
  EXPECT_GE(cut.position_sigma[1], 3.9 / 2);

  // Calibration: 2 px of noise on every edge, no pitch error: the stated range sigma against the scatter.
  LiftOptions no_pitch;
  no_pitch.pitch_sigma = 0;
  const GroundLifter pixel_only(cam, no_pitch);
  std::mt19937 rng(3);
  std::normal_distribution<double> px(0, 2.0);
  const cv::Rect2d exact = boxAt(20, 3);
  const double stated = pixel_only.lift({BESLAM_CLASS_CAR, 0.8f, exact}).position_sigma[0];
  double sum = 0, sum2 = 0;
  const int n = 400;
  for (int i = 0; i < n; ++i) {
    const double x0 = exact.x + px(rng), y0 = exact.y + px(rng), x1 = exact.br().x + px(rng),
                 y1 = exact.br().y + px(rng);
    const beslam_box3d b = pixel_only.lift({BESLAM_CLASS_CAR, 0.8f, cv::Rect2d(x0, y0, x1 - x0, y1 - y0)});
    const double r = std::hypot(b.center_cam[0], b.center_cam[2]);
    sum += r, sum2 += r * r;
  }
  const double scatter = std::sqrt(sum2 / n - (sum / n) * (sum / n));
  std::printf("car at 20 m, 2 px edge noise: range scatter %.3f m, stated %.3f m\n", scatter, stated);
  EXPECT_NEAR(scatter / stated, 1.0, 0.3);
}

TEST(ImageDetector, ModelFileErrorsNameThePath) {
  DnnOptions o;
  EXPECT_THROW(Detector2D{o}, std::invalid_argument);  // no model set
  o.model = "/nonexistent/models/net.cfg";
  o.weights = "/nonexistent/models/net.weights";
  try {
    Detector2D d(o);
    ADD_FAILURE() << "missing model accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/models/net.cfg"), std::string::npos) << e.what();
  }
  const fs::path dir = fs::temp_directory_path() / ("beslam_detimg_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string garbage = (dir / "garbage.cfg").string(), weights = (dir / "garbage.weights").string();
  std::ofstream(garbage) << "this is not a darknet network\n[convolutional]\nfilters=banana\n";
  std::ofstream(weights) << "xx";
  o.model = garbage, o.weights = weights;
  try {
    Detector2D d(o);
    ADD_FAILURE() << "garbage model accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(garbage), std::string::npos) << e.what();
  }
  if (haveModel()) {
    o.model = kCfg, o.weights = (dir / "missing.weights").string();
    try {
      Detector2D d(o);
      ADD_FAILURE() << "missing weights accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("missing.weights"), std::string::npos) << e.what();
    }
    o.weights = kWeights;
    Detector2D d(o);
    EXPECT_THROW(d.detect(cv::Mat()), std::invalid_argument);
    EXPECT_THROW(d.detect(cv::Mat(10, 10, CV_32FC1)), std::invalid_argument);
    EXPECT_NO_THROW(d.detect(cv::Mat(375, 1242, CV_8UC1, cv::Scalar(128))));
  }
  fs::remove_all(dir);
}

TEST(DetectorImagePlugin, ConfigErrorsAndDetectionThroughTheAbi) {
  beslam::test::AbiHarness plugin(PLUGIN_FILE, "detector_image");
  beslam_create_info info{};
  info.camera = kittiCamera();
  // The camera's height over the road is the dataset's (create info, ABI 1.1), not a detector setting.
  EXPECT_EQ(plugin.create({{"model", "/no/such/yolo.cfg"}, {"weights", "/no/such/yolo.weights"}}, info),
            BESLAM_ERROR_INVALID_CONFIG);
  EXPECT_NE(plugin.lastError().find("camera_height"), std::string::npos) << plugin.lastError();
  info.camera_height = 1.65;
  EXPECT_EQ(plugin.create({}, info), BESLAM_ERROR_INVALID_CONFIG);  // no model by default
  EXPECT_NE(plugin.lastError().find("model"), std::string::npos) << plugin.lastError();
  EXPECT_EQ(plugin.create({{"model", "/no/such/yolo.cfg"}, {"weights", "/no/such/yolo.weights"}}, info),
            BESLAM_ERROR_INVALID_CONFIG);
  EXPECT_NE(plugin.lastError().find("/no/such/yolo.cfg"), std::string::npos) << plugin.lastError();
  if (!haveModel() || !haveSeq06()) GTEST_SKIP() << "shared model or KITTI 06 absent: skipping the detection part";

  const cv::Mat image = cv::imread(kSeq06 + "/image_0/000020.png", cv::IMREAD_GRAYSCALE);
  info.camera = seq06Camera(image);
  EXPECT_EQ(plugin.create({{"model", kCfg}, {"weights", kWeights}, {"car_size", "[4, 2]"}}, info),
            BESLAM_ERROR_INVALID_CONFIG);
  ASSERT_EQ(plugin.create({{"model", kCfg}, {"weights", kWeights}}, info), BESLAM_OK) << plugin.lastError();
  beslam_frame frame{};
  frame.struct_size = sizeof(frame);
  frame.index = 20;
  frame.gray = beslam::sdk::toView(image, BESLAM_PIXEL_GRAY8);
  beslam_box_list out{};
  ASSERT_EQ(plugin.detect(frame, &out), BESLAM_OK) << plugin.lastError();
  ASSERT_GT(out.count, 0u);
  bool car = false;
  for (const beslam_box3d& b : beslam::sdk::copyBoxes(&out)) car = car || b.class_id == BESLAM_CLASS_CAR;
  EXPECT_TRUE(car);

  const cv::Mat small(100, 200, CV_8UC1, cv::Scalar(0));
  frame.gray = beslam::sdk::toView(small, BESLAM_PIXEL_GRAY8);
  EXPECT_EQ(plugin.detect(frame, &out), BESLAM_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(plugin.lastError().find("200x100"), std::string::npos) << plugin.lastError();
}
