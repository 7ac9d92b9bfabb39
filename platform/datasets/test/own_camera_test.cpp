// Your own camera: the camera file, and the image folder, video and EuRoC layouts, on data the tests make
// themselves from a short `beslam synth` rendering: a folder of images distorted with a known
// radial-tangential (and a fisheye) model, an MJPG video, and an EuRoC folder with sensor.yaml and ground
// truth. Each format loads with the right camera and timestamps; undistorted frames match the rendered
// ones pixel by pixel inside the valid region; every malformed camera file or layout is one error naming
// the file. (The SLAM run on distorted against undistorted images: tests/integration/own_camera_test.cpp.)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "beslam/datasets/camera_file.hpp"
#include "beslam/sim/synth.hpp"
#include "test_util.hpp"

namespace beslam::datasets {
namespace {

using test::TempDir;
using test::writeText;

constexpr int kFrames = 4;
constexpr int kWidth = 320, kHeight = 160;
constexpr double kF = 200, kCx = 161.5, kCy = 79.5;
const std::vector<double> kRadTan = {-0.28, 0.09, 0.0012, -0.0008, -0.01};  // k1 k2 p1 p2 k3
const std::vector<double> kFisheye = {0.05, -0.02, 0.004, -0.001};          // k1 k2 k3 k4

// The rendered sequence: kFrames frames of the static loop at kWidth x kHeight, grey and colour, with
// their ground-truth poses (world = camera at frame 0).
struct Rendered {
  std::vector<cv::Mat> grey, colour;
  std::vector<Eigen::Isometry3d> T_world_cam;
};

const Rendered& rendered() {
  static const Rendered r = [] {
    sim::SynthConfig c = sim::presetConfig("static_loop");
    c.frames = kFrames;
    c.camera.width = kWidth, c.camera.height = kHeight;
    c.camera.fx = c.camera.fy = kF;
    c.camera.cx = kCx, c.camera.cy = kCy;
    c.lidar.enabled = false;
    c.image.noise_sigma = 0;  // the comparisons below measure resampling, not sensor noise
    c.output.threads = 1;
    const sim::Synthesizer synth(c);
    Rendered out;
    for (int i = 0; i < kFrames; ++i) {
      const sim::FrameRender f = synth.render(i);
      out.grey.push_back(f.grey.clone());
      out.colour.push_back(f.colour.clone());
      out.T_world_cam.push_back(f.T_world_cam);
    }
    return out;
  }();
  return r;
}

cv::Matx33d K() { return cv::Matx33d(kF, 0, kCx, 0, kF, kCy, 0, 0, 1); }

// The image a camera with distortion D would have taken: for each distorted pixel, its undistorted
// position (cv::undistortPoints / cv::fisheye::undistortPoints), sampled from the pinhole image.
cv::Mat distort(const cv::Mat& pinhole, const std::vector<double>& D, bool fisheye) {
  std::vector<cv::Point2f> pixels;
  for (int y = 0; y < pinhole.rows; ++y)
    for (int x = 0; x < pinhole.cols; ++x) pixels.emplace_back(static_cast<float>(x), static_cast<float>(y));
  std::vector<cv::Point2f> ideal;
  if (fisheye)
    cv::fisheye::undistortPoints(pixels, ideal, K(), D, cv::noArray(), K());
  else
    cv::undistortPoints(pixels, ideal, K(), D, cv::noArray(), K());
  cv::Mat map(pinhole.size(), CV_32FC2);
  for (int y = 0; y < pinhole.rows; ++y)
    for (int x = 0; x < pinhole.cols; ++x) {
      const cv::Point2f& p = ideal[static_cast<std::size_t>(y * pinhole.cols + x)];
      map.at<cv::Vec2f>(y, x) = cv::Vec2f(p.x, p.y);
    }
  cv::Mat out;
  cv::remap(pinhole, out, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return out;
}

// Pixels of the undistorted image whose round trip (undistorted -> distorted -> pinhole) stays well inside
// both images: where the undistorted frame must match the rendered one.
cv::Mat validRegion(const std::vector<double>& D, bool fisheye) {
  cv::Mat mx, my;
  if (fisheye)
    cv::fisheye::initUndistortRectifyMap(K(), D, cv::Matx33d::eye(), K(), cv::Size(kWidth, kHeight), CV_32FC1, mx, my);
  else
    cv::initUndistortRectifyMap(K(), D, cv::noArray(), K(), cv::Size(kWidth, kHeight), CV_32FC1, mx, my);
  cv::Mat valid(kHeight, kWidth, CV_8U, cv::Scalar(0));
  const int margin = 4;
  for (int y = margin; y < kHeight - margin; ++y)
    for (int x = margin; x < kWidth - margin; ++x) {
      const float u = mx.at<float>(y, x), v = my.at<float>(y, x);
      if (u >= margin && v >= margin && u < kWidth - 1 - margin && v < kHeight - 1 - margin)
        valid.at<uchar>(y, x) = 255;
    }
  return valid;
}

double meanAbsDiff(const cv::Mat& a, const cv::Mat& b, const cv::Mat& mask) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  return cv::mean(diff, mask)[0];
}

std::string list(const std::vector<double>& values) {
  std::ostringstream ss;
  ss.precision(17);
  ss << "[";
  for (std::size_t k = 0; k < values.size(); ++k) ss << (k ? ", " : "") << values[k];
  ss << "]";
  return ss.str();
}

std::string cameraYaml(const std::string& model, const std::vector<double>& D, const std::string& extra = "") {
  std::ostringstream ss;
  ss.precision(17);
  ss << "model: " << model << "\nwidth: " << kWidth << "\nheight: " << kHeight << "\nfx: " << kF << "\nfy: " << kF
     << "\ncx: " << kCx << "\ncy: " << kCy << "\n";
  if (!D.empty()) ss << "distortion: " << list(D) << "\n";
  return ss.str() + extra;
}

// A folder of distorted PNGs (frame_0.png ... frame_3.png: name order must be by number) and its camera file.
void writeDistortedFolder(const std::string& folder, const std::string& camera_file, const std::vector<double>& D,
                          bool fisheye, bool with_times) {
  for (int i = 0; i < kFrames; ++i) {
    const std::string path = folder + "/frame_" + std::to_string(i * 5) + ".png";  // 0, 5, 10, 15: numeric order
    std::filesystem::create_directories(folder);
    ASSERT_TRUE(cv::imwrite(path, distort(rendered().grey[static_cast<std::size_t>(i)], D, fisheye))) << path;
  }
  if (with_times) writeText(folder + "/times.txt", "0.5\n0.6\n0.7\n0.85\n");
  writeText(camera_file, cameraYaml(fisheye ? "fisheye" : "pinhole", D, "fps: 10\nheight_over_road: 1.4\n"));
}

DatasetOptions options(const std::string& type, const std::string& root, const std::string& calibration = "") {
  DatasetOptions o;
  o.type = type;
  o.root = root;
  o.calibration = calibration;
  return o;
}

TEST(CameraFile, ReadsEveryKey) {
  TempDir dir;
  writeText(dir / "cam.yaml", cameraYaml("pinhole", kRadTan, "fps: 29.97\nheight_over_road: 1.2\n"));
  const CameraCalibration c = readCameraFile(dir / "cam.yaml");
  EXPECT_EQ(c.model, CameraModel::Pinhole);
  EXPECT_EQ(c.camera.width, kWidth);
  EXPECT_EQ(c.camera.height, kHeight);
  EXPECT_DOUBLE_EQ(c.camera.fx, kF);
  EXPECT_DOUBLE_EQ(c.camera.cx, kCx);
  EXPECT_DOUBLE_EQ(c.camera.cy, kCy);
  EXPECT_EQ(c.distortion, kRadTan);
  EXPECT_DOUBLE_EQ(*c.fps, 29.97);
  EXPECT_DOUBLE_EQ(*c.height_over_road, 1.2);
  EXPECT_TRUE(c.distorted());
  EXPECT_EQ(c.modelText(), "pinhole, radial-tangential");

  writeText(dir / "plain.yaml", cameraYaml("pinhole", {}));
  const CameraCalibration plain = readCameraFile(dir / "plain.yaml");
  EXPECT_FALSE(plain.distorted());
  EXPECT_FALSE(plain.fps);
  EXPECT_FALSE(plain.height_over_road);
  writeText(dir / "four.yaml", cameraYaml("pinhole", {0.1, 0.01, 0, 0}));
  EXPECT_EQ(readCameraFile(dir / "four.yaml").distortion, (std::vector<double>{0.1, 0.01, 0, 0, 0}));
  writeText(dir / "fisheye.yaml", cameraYaml("fisheye", kFisheye));
  const CameraCalibration fisheye = readCameraFile(dir / "fisheye.yaml");
  EXPECT_EQ(fisheye.model, CameraModel::Fisheye);
  EXPECT_EQ(fisheye.distortion, kFisheye);
  EXPECT_EQ(fisheye.modelText(), "fisheye, equidistant");
}

TEST(CameraFile, EveryBadValueIsOneErrorNamingFileAndKey) {
  TempDir dir;
  const std::string path = dir / "cam.yaml";
  auto expectError = [&](const std::string& text, std::initializer_list<std::string> parts) {
    writeText(path, text);
    try {
      readCameraFile(path);
      ADD_FAILURE() << "no error for:\n" << text;
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path, 0), 0u) << message;  // starts with the file
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      for (const std::string& part : parts)
        EXPECT_NE(message.find(part), std::string::npos) << message << " / " << part;
    }
  };
  const std::string good = cameraYaml("pinhole", {});
  auto without = [&](const std::string& key) {
    std::istringstream in(good);
    std::string out;
    for (std::string line; std::getline(in, line);)
      if (line.rfind(key + ":", 0) != 0) out += line + "\n";
    return out;
  };
  for (const char* key : {"model", "width", "height", "fx", "fy", "cx", "cy"})
    expectError(without(key), {std::string(key) + ": missing", "model, width, height, fx, fy, cx, cy"});
  expectError(without("fx") + "fx: -3\n", {":7: fx:", "'-3'", "positive focal length"});
  expectError(without("fy") + "fy: 0\n", {"fy:", "positive focal length"});
  expectError(without("fx") + "fx: .nan\n", {"fx:", "positive focal length"});
  expectError(without("cx") + "cx: .inf\n", {"cx:", "finite"});
  expectError(without("cy") + "cy: abc\n", {"cy:", "'abc'", "finite"});
  expectError(without("width") + "width: 12.5\n", {"width:", "positive whole number of pixels"});
  expectError(without("height") + "height: 0\n", {"height:", "positive whole number"});
  expectError(good + "distortion: [0.1, 0.2, 0.3]\n", {"distortion:", "has 3 values", "[k1, k2, p1, p2, k3]"});
  expectError(good + "distortion: [0.1, .nan, 0, 0, 0]\n", {"distortion:", "finite"});
  expectError(good + "distortion: 0.1\n", {"distortion:", "[k1, k2, p1, p2, k3]"});
  expectError(cameraYaml("fisheye", {0.1, 0.2, 0.3, 0.4, 0.5}), {"distortion:", "has 5 values", "[k1, k2, k3, k4]"});
  expectError(cameraYaml("fisheye", {}), {"distortion: missing", "[k1, k2, k3, k4]"});
  expectError(cameraYaml("kannala_brandt", {}),
              {":1: model:", "unknown camera model 'kannala_brandt'", "pinhole, fisheye"});
  expectError(good + "fps: 0\n", {"fps:", "positive"});
  expectError(good + "height_over_road: -1\n", {"height_over_road:", "(0, 100)"});
  expectError(good + "fxx: 3\n", {"fxx: unknown key", "known: model, width"});
  expectError(without("fx") + "fx: [1, 2\n", {"YAML syntax error"});
  expectError("- model\n- pinhole\n", {"a camera file is a map"});
  // The YAML checks every host reader makes: a key given twice, a key that is not a name.
  expectError(good + "fx: 300\n", {"duplicate key 'fx'", "first at line"});
  expectError(good + "[a]: 1\n", {"a key must be a plain name"});
  EXPECT_BESLAM_ERROR(readCameraFile(dir / "absent.yaml"), dir / "absent.yaml", "cannot read the camera file");
}

TEST(ImageFolder, DistortedImagesLoadUndistortedOntoTheSameK) {
  TempDir dir;
  for (const bool fisheye : {false, true}) {
    SCOPED_TRACE(fisheye ? "fisheye" : "radial-tangential");
    const std::vector<double>& D = fisheye ? kFisheye : kRadTan;
    const std::string folder = dir / (fisheye ? "fisheye" : "radtan"), cam = folder + ".yaml";
    writeDistortedFolder(folder, cam, D, fisheye, true);
    const auto ds = openDataset(options("images", folder, cam));
    ASSERT_EQ(ds->size(), 4u);
    EXPECT_EQ(ds->camera().width, kWidth);
    EXPECT_EQ(ds->camera().height, kHeight);
    EXPECT_DOUBLE_EQ(ds->camera().fx, kF);
    EXPECT_DOUBLE_EQ(ds->camera().cy, kCy);
    EXPECT_DOUBLE_EQ(*ds->cameraHeight(), 1.4);
    EXPECT_FALSE(ds->groundTruth());
    EXPECT_NE(ds->describe().find(std::string("4 frames, times.txt, camera file ") + (fisheye ? "fisheye" : "radtan") +
                                  ".yaml (" + (fisheye ? "fisheye, equidistant" : "pinhole, radial-tangential") +
                                  ", undistorted)"),
              std::string::npos)
        << ds->describe();
    const cv::Mat valid = validRegion(D, fisheye);
    EXPECT_GT(cv::countNonZero(valid), kWidth * kHeight / 2);
    const double times[] = {0.5, 0.6, 0.7, 0.85};
    double worst_undistorted = 0, best_distorted = 255;
    for (std::size_t i = 0; i < ds->size(); ++i) {
      const Frame f = ds->load(i);
      EXPECT_EQ(f.index, static_cast<std::int64_t>(i));
      EXPECT_DOUBLE_EQ(f.timestamp, times[i]);
      EXPECT_NE(f.image_path.find("frame_" + std::to_string(5 * i) + ".png"), std::string::npos) << f.image_path;
      ASSERT_EQ(f.gray.size(), cv::Size(kWidth, kHeight));
      const double undistorted = meanAbsDiff(f.gray, rendered().grey[i], valid);
      const double distorted = meanAbsDiff(cv::imread(f.image_path, cv::IMREAD_GRAYSCALE), rendered().grey[i], valid);
      // Two bilinear resamplings of a noisy rendering: a few grey levels; the distorted image is far off.
      EXPECT_LT(undistorted, 4.0) << "frame " << i;
      EXPECT_GT(distorted, 3 * undistorted + 4.0) << "frame " << i;
      worst_undistorted = std::max(worst_undistorted, undistorted);
      best_distorted = std::min(best_distorted, distorted);
    }
    std::printf(
        "[ %s ] mean |undistorted - rendered| <= %.2f grey levels in the valid region (%.0f %% of the image); "
        "the distorted images: >= %.2f\n",
        fisheye ? "fisheye" : "radial-tangential", worst_undistorted,
        100.0 * cv::countNonZero(valid) / (kWidth * kHeight), best_distorted);
  }
}

TEST(ImageFolder, TimestampsFromFpsOrTimesTxtOrAnError) {
  TempDir dir;
  const std::string folder = dir / "images", cam = dir / "cam.yaml";
  writeDistortedFolder(folder, cam, kRadTan, false, false);
  DatasetOptions o = options("images", folder, cam);
  o.first = 1;
  o.step = 2;
  const auto ds = openDataset(o);  // camera file's fps: 10
  ASSERT_EQ(ds->size(), 2u);
  EXPECT_EQ(ds->frameNumber(0), 1);
  EXPECT_DOUBLE_EQ(ds->load(0).timestamp, 0.1);
  EXPECT_DOUBLE_EQ(ds->load(1).timestamp, 0.3);
  EXPECT_NE(ds->describe().find("10 fps"), std::string::npos) << ds->describe();

  writeText(cam, cameraYaml("pinhole", kRadTan));  // no fps, no times.txt
  EXPECT_BESLAM_ERROR(openDataset(options("images", folder, cam)), folder + "/times.txt", "missing", cam, "no fps");
  writeText(folder + "/times.txt", "0\n0.1\n0.2\n");
  EXPECT_BESLAM_ERROR(openDataset(options("images", folder, cam)), folder + "/times.txt", "has 3 timestamps",
                      "4 images");
  writeText(folder + "/times.txt", "0\n0.1\n0.1\n0.3\n");
  EXPECT_BESLAM_ERROR(openDataset(options("images", folder, cam)), folder + "/times.txt", "must increase");
  writeText(folder + "/times.txt", "0\n0.1\nx\n0.3\n");
  EXPECT_BESLAM_ERROR(openDataset(options("images", folder, cam)), folder + "/times.txt:3:", "timestamp in seconds");
  writeText(folder + "/times.txt", "0\n0.1\n0.2\n0.3\n");
  EXPECT_EQ(openDataset(options("images", folder, cam))->load(3).timestamp, 0.3);

  EXPECT_BESLAM_ERROR(openDataset(options("images", folder)), folder, "dataset.calibration");
  writeText(dir / "small.yaml", "model: pinhole\nwidth: 64\nheight: 48\nfx: 50\nfy: 50\ncx: 32\ncy: 24\n");
  EXPECT_BESLAM_ERROR(openDataset(options("images", folder, dir / "small.yaml")), dir / "small.yaml",
                      "64x48 but " + folder + "/frame_0.png is 320x160");
  std::filesystem::create_directories(dir / "empty");
  writeText(dir / "empty/notes.txt", "no images here\n");
  EXPECT_BESLAM_ERROR(openDataset(options("images", dir / "empty", cam)), dir / "empty", "no images", ".png");
  EXPECT_BESLAM_ERROR(openDataset(options("images", dir / "absent", cam)), dir / "absent", "missing image folder");
  cv::imwrite(folder + "/frame_20.png", cv::Mat(10, 10, CV_8U, cv::Scalar(0)));
  writeText(folder + "/times.txt", "0\n0.1\n0.2\n0.3\n0.4\n");
  EXPECT_BESLAM_ERROR(openDataset(options("images", folder, cam))->load(4), folder + "/frame_20.png", "10x10",
                      "320x160");
}

TEST(Video, LoadsFramesWithContainerOrCameraFileTimestamps) {
  TempDir dir;
  const std::string video = dir / "drive.avi";
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(kWidth, kHeight), true);
    if (!writer.isOpened()) GTEST_SKIP() << "this OpenCV cannot write MJPG into .avi (no video writer backend)";
    for (const cv::Mat& colour : rendered().colour) writer.write(colour);
  }
  writeText(dir / "cam.yaml", cameraYaml("pinhole", {}));
  DatasetOptions o = options("video", video, dir / "cam.yaml");
  o.load_color = true;
  const auto ds = openDataset(o);
  ASSERT_EQ(ds->size(), 4u);
  EXPECT_EQ(ds->camera().width, kWidth);
  EXPECT_DOUBLE_EQ(ds->camera().fx, kF);
  EXPECT_FALSE(ds->cameraHeight());
  EXPECT_NE(ds->describe().find("video drive.avi (4 frames"), std::string::npos) << ds->describe();
  const cv::Mat all(kHeight, kWidth, CV_8U, cv::Scalar(255));
  for (const std::size_t i : {2u, 3u, 0u, 1u}) {  // forwards, then back to the start (the file is reopened)
    const Frame f = ds->load(i);
    EXPECT_EQ(f.index, static_cast<std::int64_t>(i));
    EXPECT_NEAR(f.timestamp, 0.1 * static_cast<double>(i), 1e-9);
    EXPECT_EQ(f.image_path, video + "#" + std::to_string(i));
    ASSERT_EQ(f.gray.type(), CV_8UC1);
    ASSERT_EQ(f.color.type(), CV_8UC3);
    EXPECT_LT(meanAbsDiff(f.gray, rendered().grey[i], all), 4.0) << "frame " << i;  // MJPEG is lossy
    EXPECT_LT(meanAbsDiff(f.color, rendered().colour[i], all), 5.0) << "frame " << i;
    EXPECT_GT(meanAbsDiff(f.gray, rendered().grey[(i + 2) % 4], all), 10.0) << "frame " << i << " is another frame";
  }

  writeText(dir / "cam.yaml", cameraYaml("pinhole", kRadTan, "fps: 20\n"));
  o.first = 1;
  const auto at20 = openDataset(o);
  ASSERT_EQ(at20->size(), 3u);
  EXPECT_DOUBLE_EQ(at20->load(0).timestamp, 0.05);
  EXPECT_DOUBLE_EQ(at20->load(2).timestamp, 0.15);
  EXPECT_NE(
      at20->describe().find("20 fps (camera file), camera file cam.yaml (pinhole, radial-tangential, undistorted)"),
      std::string::npos)
      << at20->describe();

  EXPECT_BESLAM_ERROR(openDataset(options("video", video)), video, "dataset.calibration");
  EXPECT_BESLAM_ERROR(openDataset(options("video", dir / "absent.avi", dir / "cam.yaml")), dir / "absent.avi",
                      "missing video file");
  writeText(dir / "notes.avi", "not a video at all\n");
  EXPECT_BESLAM_ERROR(openDataset(options("video", dir / "notes.avi", dir / "cam.yaml")), dir / "notes.avi",
                      "cannot open");
  writeText(dir / "wide.yaml", "model: pinhole\nwidth: 640\nheight: 160\nfx: 50\nfy: 50\ncx: 32\ncy: 24\n");
  EXPECT_BESLAM_ERROR(openDataset(options("video", video, dir / "wide.yaml")), dir / "wide.yaml", "640x160 but", video,
                      "320x160");
}

// An EuRoC/ASL folder: cam0 (data.csv, data/<ns>.png distorted with 4 radial-tangential coefficients,
// sensor.yaml with a body-to-camera T_BS) and state_groundtruth_estimate0 (body poses at 200 Hz).
struct Euroc {
  std::string root;
  Eigen::Isometry3d T_BS = Eigen::Isometry3d::Identity();
  std::int64_t t0 = 1403636579763555584;
  std::int64_t stamp(int i) const { return t0 + 100000000LL * i; }  // 10 Hz
};

Euroc writeEuroc(const TempDir& dir) {
  Euroc e;
  e.root = dir / "MH_01_easy";
  const std::string cam = e.root + "/mav0/cam0";
  const std::vector<double> D = {kRadTan[0], kRadTan[1], kRadTan[2], kRadTan[3]};
  std::string csv = "#timestamp [ns],filename\n";
  for (int i = 0; i < kFrames; ++i) {
    const std::string name = std::to_string(e.stamp(i)) + ".png";
    std::filesystem::create_directories(cam + "/data");
    cv::imwrite(cam + "/data/" + name, distort(rendered().grey[static_cast<std::size_t>(i)], D, false));
    csv += std::to_string(e.stamp(i)) + "," + name + "\r\n";  // EuRoC's files have CRLF line ends
  }
  writeText(cam + "/data.csv", csv);
  e.T_BS.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  e.T_BS.translation() = Eigen::Vector3d(-0.02, 0.06, 0.01);
  std::ostringstream T;
  T.precision(17);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) T << (r || c ? ", " : "") << e.T_BS.matrix()(r, c);
  std::ostringstream sensor;
  sensor.precision(17);
  sensor << "%YAML:1.0\n# General sensor definitions.\nsensor_type: camera\ncomment: VI-Sensor cam0 (MT9M034)\n"
         << "T_BS:\n  cols: 4\n  rows: 4\n  data: [" << T.str() << "]\n"
         << "rate_hz: 10\nresolution: [" << kWidth << ", " << kHeight << "]\ncamera_model: pinhole\n"
         << "intrinsics: [" << kF << ", " << kF << ", " << kCx << ", " << kCy << "] #fu, fv, cu, cv\n"
         << "distortion_model: radial-tangential\ndistortion_coefficients: " << list(D) << "\n";
  writeText(cam + "/sensor.yaml", sensor.str());
  // Body poses T_world_body = T_world_cam * T_BS^-1 at the frames and 4 samples between (interpolated
  // positions, the frame's rotation: frames are 10 Hz, ground truth 50 Hz here).
  std::ostringstream gt;
  gt.precision(17);
  gt << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
        "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
        "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n";
  for (int i = 0; i < kFrames; ++i)
    for (int k = 0; k < (i + 1 < kFrames ? 5 : 1); ++k) {
      const Eigen::Isometry3d A = rendered().T_world_cam[static_cast<std::size_t>(i)] * e.T_BS.inverse();
      Eigen::Isometry3d T_world_body = A;
      if (k > 0) {
        const Eigen::Isometry3d B = rendered().T_world_cam[static_cast<std::size_t>(i + 1)] * e.T_BS.inverse();
        T_world_body.translation() = A.translation() + (B.translation() - A.translation()) * (k / 5.0);
      }
      const Eigen::Quaterniond q(T_world_body.linear());
      const Eigen::Vector3d p = T_world_body.translation();
      gt << e.stamp(i) + 20000000LL * k << "," << p.x() << "," << p.y() << "," << p.z() << "," << q.w() << "," << q.x()
         << "," << q.y() << "," << q.z() << ",0,0,0,0,0,0,0,0,0\n";
    }
  writeText(e.root + "/mav0/state_groundtruth_estimate0/data.csv", gt.str());
  return e;
}

TEST(Euroc, ReadsCameraFromSensorYamlAndGroundTruthAsCameraPoses) {
  TempDir dir;
  const Euroc e = writeEuroc(dir);
  DatasetOptions o = options("euroc", e.root);
  o.calibration = "";
  const auto ds = openDataset(o);
  ASSERT_EQ(ds->size(), 4u);
  EXPECT_EQ(ds->camera().width, kWidth);
  EXPECT_DOUBLE_EQ(ds->camera().fx, kF);
  EXPECT_DOUBLE_EQ(ds->camera().cx, kCx);
  EXPECT_EQ(ds->describe(),
            "EuRoC MH_01_easy (4 frames, cam0, camera file sensor.yaml (pinhole, radial-tangential, undistorted), "
            "ground truth for 4/4 frames)");
  const cv::Mat valid = validRegion(kRadTan, false);
  const auto gt = ds->groundTruth();
  ASSERT_TRUE(gt);
  ASSERT_EQ(gt->size(), 4u);
  for (std::size_t i = 0; i < ds->size(); ++i) {
    const Frame f = ds->load(i);
    EXPECT_DOUBLE_EQ(f.timestamp, static_cast<double>(e.stamp(static_cast<int>(i))) * 1e-9);
    EXPECT_EQ(gt->stamps[i], f.timestamp);
    // T_world_body * T_BS gives back the camera's pose (up to the 1e-7 s that absolute times in seconds
    // keep of the nanoseconds, which moves the interpolation by some 1e-6 m).
    const Eigen::Isometry3d& truth = rendered().T_world_cam[i];
    EXPECT_LT((gt->poses[i].translation() - truth.translation()).norm(), 1e-5) << "frame " << i;
    EXPECT_LT((gt->poses[i].linear() - truth.linear()).norm(), 1e-5) << "frame " << i;
    EXPECT_LT(meanAbsDiff(f.gray, rendered().grey[i], valid), 4.0) << "frame " << i;
  }
  // With `mav0` as the root, and a camera file in place of sensor.yaml's camera (T_BS stays sensor.yaml's).
  writeText(dir / "cam.yaml", cameraYaml("pinhole", {}, "height_over_road: 0.8\n"));
  const auto own = openDataset(options("euroc", e.root + "/mav0", dir / "cam.yaml"));
  EXPECT_NE(own->describe().find("camera file cam.yaml (pinhole)"), std::string::npos) << own->describe();
  EXPECT_DOUBLE_EQ(*own->cameraHeight(), 0.8);
  EXPECT_LT((own->groundTruth()->poses[2].translation() - rendered().T_world_cam[2].translation()).norm(), 1e-5);
}

TEST(Euroc, EveryMalformedFileIsOneErrorNamingIt) {
  TempDir dir;
  const Euroc e = writeEuroc(dir);
  const std::string cam = e.root + "/mav0/cam0";
  const std::string sensor = test::readBytes(cam + "/sensor.yaml");
  auto open = [&] { return openDataset(options("euroc", e.root)); };

  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = sensor;
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };
  writeText(cam + "/sensor.yaml", replaced("intrinsics:", "intrinsic:"));
  EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml", "intrinsics: missing", "[fu, fv, cu, cv]");
  writeText(cam + "/sensor.yaml", replaced("resolution: [320, 160]", "resolution: [320]"));
  EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml:", "resolution:", "[width, height]");
  writeText(cam + "/sensor.yaml", replaced("distortion_model: radial-tangential", "distortion_model: fov"));
  EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml", "distortion_model: 'fov'", "radial-tangential, equidistant");
  writeText(cam + "/sensor.yaml",
            replaced("distortion_model: radial-tangential", "distortion_model: equidistant") + "\n");
  EXPECT_NO_THROW(open());  // 4 coefficients are a valid equidistant model too
  writeText(cam + "/sensor.yaml", replaced("data: [", "data: [2, "));
  EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml:", "T_BS.data", "16 numbers");
  writeText(cam + "/sensor.yaml", sensor);
  {
    std::string text = sensor;
    const std::size_t at = text.find("data: [") + 7;
    text.replace(at, text.find(',', at) - at, "3");  // R(0,0) = 3: not a rotation
    writeText(cam + "/sensor.yaml", text);
    EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml", "T_BS", "not a rigid transform");
  }
  writeText(cam + "/sensor.yaml", sensor + "\nresolution: [640, 160]\n");
  EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml:", "duplicate key 'resolution'");
  writeText(cam + "/sensor.yaml", replaced("intrinsics: [200", "intrinsics: [-200"));
  EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml", "intrinsics", "positive");
  writeText(cam + "/sensor.yaml", replaced("resolution: [320, 160]", "resolution: [640, 160]"));
  EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml", "640x160 but", "320x160");
  std::filesystem::remove(cam + "/sensor.yaml");
  EXPECT_BESLAM_ERROR(open(), cam + "/sensor.yaml", "missing camera description sensor.yaml");
  writeText(cam + "/sensor.yaml", sensor);

  const std::string csv = test::readBytes(cam + "/data.csv");
  writeText(cam + "/data.csv", csv + "1403636580163555584\n");
  EXPECT_BESLAM_ERROR(open(), cam + "/data.csv:6:", "timestamp [ns],filename");
  writeText(cam + "/data.csv", csv + "14036365801635x,a.png\n");
  EXPECT_BESLAM_ERROR(open(), cam + "/data.csv:6:", "not a timestamp in nanoseconds");
  writeText(cam + "/data.csv", csv + "1403636579763555584,a.png\n");
  EXPECT_BESLAM_ERROR(open(), cam + "/data.csv:6:", "not increasing");
  writeText(cam + "/data.csv", csv + "1403636580163555584,absent.png\n");
  EXPECT_BESLAM_ERROR(open(), cam + "/data/absent.png", "missing image", "data.csv");
  writeText(cam + "/data.csv", "#timestamp [ns],filename\n");
  EXPECT_BESLAM_ERROR(open(), cam + "/data.csv", "lists no images");
  writeText(cam + "/data.csv", csv);

  const std::string gt_path = e.root + "/mav0/state_groundtruth_estimate0/data.csv";
  const std::string gt = test::readBytes(gt_path);
  writeText(gt_path, gt + "1403636580163555584,1,2,3\n");
  EXPECT_BESLAM_ERROR(open(), gt_path + ":18:", "at least 8");
  writeText(gt_path, gt + "1403636580163555584,1,2,3,0,0,0,0\n");
  EXPECT_BESLAM_ERROR(open(), gt_path + ":18:", "unit length");
  writeText(gt_path, gt + "1403636580163555584,1,2,x,1,0,0,0\n");
  EXPECT_BESLAM_ERROR(open(), gt_path + ":18:", "'x' is not a number");
  std::filesystem::remove(gt_path);
  EXPECT_FALSE(open()->groundTruth());  // ground truth is optional

  DatasetOptions wrong = options("euroc", e.root);
  wrong.camera = "image_2";
  EXPECT_BESLAM_ERROR(openDataset(wrong), "euroc reads cam0");
  std::filesystem::remove_all(cam);
  EXPECT_BESLAM_ERROR(open(), cam, "missing camera folder", "mav0/cam0/data.csv");
}

}  // namespace
}  // namespace beslam::datasets
