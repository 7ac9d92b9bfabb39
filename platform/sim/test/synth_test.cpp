// beslam_sim: config validation, determinism, file layout, projection consistency (boxes vs masks,
// LiDAR vs rendered depth), texture richness (FAST corners) and motion ground truth.
#include "beslam/sim/synth.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/sim/car_mesh.hpp"

namespace fs = std::filesystem;
using beslam::sim::SynthConfig;

namespace {

std::string tempDir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("beslam_sim_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

// A tiny but complete sequence: 320 x 96 pixels, 6 frames, a coarse LiDAR, something of every behaviour.
SynthConfig tinyConfig() {
  SynthConfig c = beslam::sim::presetConfig("dynamic_street");
  c.frames = 6;
  const double s = 320.0 / 1241.0;
  c.camera.width = 320, c.camera.height = 96;
  c.camera.fx = c.camera.fy = 718.856 * s;
  c.camera.cx = 607.1928 * s, c.camera.cy = 185.2157 * s;
  c.lidar.horizontal_resolution_deg = 1.0;
  c.lidar.beams = 16;
  c.objects.parked = 8, c.objects.driving = 4, c.objects.stop_and_go = 2, c.objects.pedestrians = 4;
  c.output.depth = true;
  return c;
}

std::string slurp(const fs::path& p) { return beslam::readFile(p.string()); }

double iou(double a0, double b0, double a1, double b1, double c0, double d0, double c1, double d1) {
  const double ix = std::max(0.0, std::min(a1, c1) - std::max(a0, c0)),
               iy = std::max(0.0, std::min(b1, d1) - std::max(b0, d0));
  const double inter = ix * iy;
  const double uni = (a1 - a0) * (b1 - b0) + (c1 - c0) * (d1 - d0) - inter;
  return uni > 0 ? inter / uni : 0;
}

}  // namespace

TEST(SynthConfig, PresetsMatchTheConfigFiles) {
  for (const auto& name : beslam::sim::presetNames()) {
    const std::string path = std::string(BESLAM_SOURCE_DIR) + "/configs/synth/" + name + ".yaml";
    ASSERT_TRUE(fs::exists(path)) << path;
    EXPECT_EQ(beslam::sim::synthConfigToYaml(beslam::sim::loadSynthConfig(path)),
              beslam::sim::synthConfigToYaml(beslam::sim::presetConfig(name)))
        << name;
  }
  EXPECT_GE(beslam::sim::presetNames().size(), 5u);
  // urban_loop spells out the defaults.
  EXPECT_EQ(beslam::sim::synthConfigToYaml(beslam::sim::presetConfig("urban_loop")),
            beslam::sim::synthConfigToYaml(SynthConfig{}));
}

TEST(SynthConfig, RejectsUnknownKeysWrongTypesAndRanges) {
  auto expectError = [](const std::string& yaml, const std::string& needle) {
    try {
      beslam::sim::synthConfigFromYaml(YAML::Load(yaml), "cfg.yaml");
      ADD_FAILURE() << "no error for " << yaml;
    } catch (const beslam::Error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("cfg.yaml"), std::string::npos) << msg;
      EXPECT_NE(msg.find(needle), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  };
  expectError("framez: 3", "unknown key 'framez'");
  expectError("objects: {parkd: 3}", "unknown key 'objects.parkd'");
  expectError("frames: many", "key 'frames': expected an integer");
  expectError("frames: 0", "out of range");
  expectError("lidar: {enabled: maybe}", "expected true or false");
  expectError("world: {type: moon}", "not one of");
  expectError("camera: 3", "expected a map");
  const SynthConfig c = beslam::sim::synthConfigFromYaml(YAML::Load("frames: 12\nlidar: {enabled: false}"), "x");
  EXPECT_EQ(c.frames, 12);
  EXPECT_FALSE(c.lidar.enabled);
}

TEST(SynthConfig, SetOverridesAndCommandErrors) {
  const std::string path = std::string(BESLAM_SOURCE_DIR) + "/configs/synth/urban_loop.yaml";
  const SynthConfig c = beslam::sim::loadSynthConfig(path, {"frames=7", "objects.parked=3"});
  EXPECT_EQ(c.frames, 7);
  EXPECT_EQ(c.objects.parked, 3);
  std::ostringstream out, err;
  EXPECT_EQ(beslam::sim::runSynthCommand({"--bogus"}, out, err), 2);
  EXPECT_EQ(beslam::sim::runSynthCommand({"--config"}, out, err), 2);
  EXPECT_EQ(beslam::sim::runSynthCommand({"--help"}, out, err), 0);
  std::ostringstream err2;
  const std::string dir = tempDir("cli");
  EXPECT_EQ(beslam::sim::runSynthCommand({"--config", path, "--out", dir, "--set", "objects.parkd=3"}, out, err2), 1);
  const std::string msg = err2.str();
  EXPECT_NE(msg.find("urban_loop.yaml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("objects.parkd"), std::string::npos) << msg;
  EXPECT_EQ(std::count(msg.begin(), msg.end(), '\n'), 1) << msg;
  fs::remove_all(dir);
}

TEST(Synth, TinySequenceIsDeterministicAndKittiShaped) {
  SynthConfig c = tinyConfig();
  const std::string a = tempDir("a"), b = tempDir("b");
  c.output.threads = 2;
  const auto sa = beslam::sim::generateSequence(c, a);
  c.output.threads = 1;  // a different worker count must not change a byte
  beslam::sim::generateSequence(c, b);
  EXPECT_GT(sa.parked + sa.driving + sa.stop_and_go + sa.pedestrians, 8);

  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(a))
    if (e.is_regular_file()) files.push_back(fs::relative(e.path(), a));
  std::sort(files.begin(), files.end());
  ASSERT_GT(files.size(), 40u);
  for (const auto& f : files) {
    ASSERT_TRUE(fs::exists(fs::path(b) / f)) << f;
    EXPECT_TRUE(slurp(fs::path(a) / f) == slurp(fs::path(b) / f)) << "differs: " << f;
  }

  const fs::path seq = fs::path(a) / "sequences" / "00";
  for (const char* p : {"calib.txt", "times.txt", "label_02/00.txt", "objects_motion.txt", "manifest.yaml",
                        "objects/poses.txt", "objects/objects.txt", "image_0/000005.png", "image_2/000005.png",
                        "velodyne/000005.bin", "instance/000005.png", "depth/000005.png"})
    EXPECT_TRUE(fs::exists(seq / p)) << p;
  EXPECT_TRUE(fs::exists(fs::path(a) / "poses" / "00.txt"));

  // calib.txt: named rows, 12 or 9 numbers each.
  std::istringstream calib(slurp(seq / "calib.txt"));
  std::string line;
  std::vector<std::string> names;
  while (std::getline(calib, line)) {
    std::istringstream ls(line);
    std::string name;
    ls >> name;
    names.push_back(name);
    int count = 0;
    double x;
    while (ls >> x) ++count;
    EXPECT_EQ(count, name == "R0_rect:" ? 9 : 12) << line;
  }
  EXPECT_EQ(names, (std::vector<std::string>{"P0:", "P1:", "P2:", "P3:", "R0_rect:", "Tr_velo_to_cam:", "Tr:"}));

  // Poses: one row per frame, the first the identity.
  std::istringstream poses(slurp(fs::path(a) / "poses" / "00.txt"));
  int rows = 0;
  while (std::getline(poses, line)) {
    std::istringstream ls(line);
    std::vector<double> v;
    double x;
    while (ls >> x) v.push_back(x);
    ASSERT_EQ(v.size(), 12u);
    if (rows == 0) {
      for (int k = 0; k < 12; ++k) EXPECT_NEAR(v[k], (k == 0 || k == 5 || k == 10) ? 1.0 : 0.0, 1e-9);
    }
    ++rows;
  }
  EXPECT_EQ(rows, c.frames);

  // Labels: 17 fields, known types, track ids present in the masks.
  std::istringstream labels(slurp(seq / "label_02" / "00.txt"));
  int nlabels = 0;
  while (std::getline(labels, line)) {
    std::istringstream ls(line);
    std::vector<std::string> f;
    std::string tok;
    while (ls >> tok) f.push_back(tok);
    ASSERT_EQ(f.size(), 17u) << line;
    EXPECT_TRUE(f[2] == "Car" || f[2] == "Van" || f[2] == "Pedestrian") << line;
    const int frame = std::stoi(f[0]), id = std::stoi(f[1]);
    const cv::Mat mask = cv::imread(
        (seq / "instance" / (std::string(6 - std::to_string(frame).size(), '0') + std::to_string(frame) + ".png"))
            .string(),
        cv::IMREAD_UNCHANGED);
    ASSERT_EQ(mask.type(), CV_16UC1);
    EXPECT_GT(cv::countNonZero(mask == id), 0) << line;
    ++nlabels;
  }
  EXPECT_GT(nlabels, 0);

  // LiDAR: float32 quadruples, HDL-64-like geometry (below +2 deg elevation, within range).
  const std::string bin = slurp(seq / "velodyne" / "000003.bin");
  ASSERT_EQ(bin.size() % 16, 0u);
  const float* pts = reinterpret_cast<const float*>(bin.data());
  const std::size_t npts = bin.size() / 16;
  EXPECT_GT(npts, 1000u);
  for (std::size_t i = 0; i < npts; ++i) {
    const float x = pts[4 * i], y = pts[4 * i + 1], z = pts[4 * i + 2], in = pts[4 * i + 3];
    const float r = std::sqrt(x * x + y * y + z * z);
    EXPECT_LE(r, c.lidar.max_range + 0.1);
    EXPECT_LE(std::asin(z / r) * 180 / M_PI, c.lidar.fov_up_deg + 0.1);
    EXPECT_TRUE(in >= 0 && in <= 1);
  }

  // Manifest records the seed and the counts.
  const YAML::Node m = YAML::LoadFile((seq / "manifest.yaml").string());
  EXPECT_EQ(m["seed"].as<std::uint64_t>(), c.seed);
  EXPECT_EQ(m["counts"]["parked"].as<int>(), sa.parked);
  EXPECT_EQ(m["config"]["frames"].as<int>(), c.frames);
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST(Synth, MotionFlagsAgreeWithTrajectories) {
  SynthConfig c = beslam::sim::presetConfig("dynamic_street");
  c.frames = 300;
  const beslam::sim::Synthesizer synth(c);
  int moving = 0, still = 0, pullouts = 0;
  for (const auto& o : synth.objects()) {
    bool everMoved = false, everStill = false;
    for (int i = 0; i + 1 < c.frames; ++i) {
      const auto s0 = synth.objectState(o.track_id, i), s1 = synth.objectState(o.track_id, i + 1);
      const double step = (s1.T_world_obj.translation() - s0.T_world_obj.translation()).norm();
      if (!s0.moving && !s1.moving) {
        EXPECT_LT(step, 1e-9) << o.track_id << " frame " << i;
      }
      if (s0.moving && s1.moving) {
        EXPECT_NEAR(step, 0.5 * (s0.speed + s1.speed) / c.rate_hz, 0.05 + 0.02 * s0.speed) << o.track_id;
      }
      everMoved = everMoved || s0.moving;
      everStill = everStill || !s0.moving;
    }
    switch (o.behaviour) {
      case beslam::sim::Behaviour::Parked:
        EXPECT_FALSE(everMoved) << o.track_id;
        break;
      case beslam::sim::Behaviour::Driving:
        EXPECT_FALSE(everStill) << o.track_id;
        break;
      case beslam::sim::Behaviour::StopAndGo:
        EXPECT_TRUE(everMoved && everStill) << o.track_id;
        ++pullouts;
        break;
      default:
        break;
    }
    (everMoved ? moving : still)++;
  }
  EXPECT_GT(moving, 10);
  EXPECT_GT(still, 5);
  EXPECT_GT(pullouts, 0);
  // Cars stay on the road and upright; poses are proper rotations.
  for (const auto& o : synth.objects()) {
    const auto s = synth.objectState(o.track_id, 0);
    EXPECT_NEAR(s.T_world_obj.linear().determinant(), 1.0, 1e-9);
  }
}

TEST(Synth, BoxesProjectOntoMasksAndLidarLandsOnDepth) {
  SynthConfig c = beslam::sim::presetConfig("urban_loop");
  const beslam::sim::Synthesizer synth(c);
  const auto P = synth.projection();
  const Eigen::Isometry3d T_cam_velo = synth.T_cam_velo();
  std::vector<double> ious, errors;
  for (int frame : {0, 40, 90, 160, 230, 300}) {
    const auto fr = synth.render(frame);
    for (const auto& L : fr.labels) {
      if (L.occluded != 0 || L.truncated > 0.02 || L.type == "Pedestrian") continue;
      // Hull of the projected 3D box.
      double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
      bool ok = true;
      for (int k = 0; k < 8; ++k) {
        const double x = (k & 1 ? 0.5 : -0.5) * L.l, y = (k & 2) ? -L.h : 0.0, z = (k & 4 ? 0.5 : -0.5) * L.w;
        const Eigen::Vector3d p(L.location.x() + std::cos(L.ry) * x + std::sin(L.ry) * z, L.location.y() + y,
                                L.location.z() - std::sin(L.ry) * x + std::cos(L.ry) * z);
        if (p.z() < 0.2) ok = false;
        const double u = P(0, 0) * p.x() / p.z() + P(0, 2), v = P(1, 1) * p.y() / p.z() + P(1, 2);
        u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
      }
      if (!ok) continue;
      const cv::Mat m = fr.instance == L.track_id;
      const cv::Rect r = cv::boundingRect(m);
      ious.push_back(iou(u0, v0, u1, v1, r.x - 0.5, r.y - 0.5, r.x + r.width - 0.5, r.y + r.height - 0.5));
      EXPECT_GT(ious.back(), 0.7) << "frame " << frame << " track " << L.track_id;
    }
    // LiDAR points against the rendered depth (1/z is affine on a plane: interpolate it bilinearly
    // where all four neighbours belong to the same surface).
    for (std::size_t i = 0; i + 3 < fr.lidar.size(); i += 4) {
      const Eigen::Vector3d pc = T_cam_velo * Eigen::Vector3d(fr.lidar[i], fr.lidar[i + 1], fr.lidar[i + 2]);
      if (pc.z() < 1.0) continue;
      const double u = P(0, 0) * pc.x() / pc.z() + P(0, 2), v = P(1, 1) * pc.y() / pc.z() + P(1, 2);
      const int x0 = static_cast<int>(std::floor(u)), y0 = static_cast<int>(std::floor(v));
      if (x0 < 0 || y0 < 0 || x0 + 1 >= fr.depth.cols || y0 + 1 >= fr.depth.rows) continue;
      const float d00 = fr.depth.at<float>(y0, x0), d10 = fr.depth.at<float>(y0, x0 + 1);
      const float d01 = fr.depth.at<float>(y0 + 1, x0), d11 = fr.depth.at<float>(y0 + 1, x0 + 1);
      if (d00 <= 0 || d10 <= 0 || d01 <= 0 || d11 <= 0) continue;
      const double fx = u - x0, fy = v - y0;
      const double iz = (1 - fy) * ((1 - fx) / d00 + fx / d10) + fy * ((1 - fx) / d01 + fx / d11);
      errors.push_back(std::abs(1.0 / iz - pc.z()));
    }
  }
  ASSERT_GT(ious.size(), 5u);
  ASSERT_GT(errors.size(), 10000u);
  std::sort(ious.begin(), ious.end());
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  const double median = errors[errors.size() / 2];
  std::cout << "[ figures ] unoccluded boxes " << ious.size() << ", IoU min " << ious.front() << " median "
            << ious[ious.size() / 2] << "; LiDAR points " << errors.size() << ", median depth error " << median * 100
            << " cm\n";
  EXPECT_LT(median, 0.02);
}

TEST(Synth, FramesHaveKittiDensityCorners) {
  const beslam::sim::Synthesizer synth(beslam::sim::presetConfig("urban_loop"));
  // Reference: OpenCV FAST-20 finds 2662-4607 corners on the KITTI 00 frames in ../shared/data.
  std::size_t total = 0;
  const std::vector<int> frames = {0, 120, 250, 400};
  for (int frame : frames) {
    const auto fr = synth.render(frame);
    std::vector<cv::KeyPoint> kps;
    cv::FAST(fr.grey, kps, 20, true);
    // Spread: corners in at least 3/4 of a 8 x 4 grid of cells.
    std::vector<int> cells(32, 0);
    for (const auto& k : kps)
      cells[std::min(3, static_cast<int>(k.pt.y * 4 / fr.grey.rows)) * 8 +
            std::min(7, static_cast<int>(k.pt.x * 8 / fr.grey.cols))]++;
    const int covered = static_cast<int>(std::count_if(cells.begin(), cells.end(), [](int n) { return n > 5; }));
    std::cout << "[ figures ] frame " << frame << ": " << kps.size() << " FAST-20 corners, " << covered
              << "/32 cells\n";
    EXPECT_GT(kps.size(), 2500u) << "frame " << frame;
    EXPECT_GE(covered, 20) << "frame " << frame;
    total += kps.size();
  }
  EXPECT_GT(total / frames.size(), 3000u);
}

TEST(Synth, EgoDrivesAClosedLoopAtKittiSpeeds) {
  const beslam::sim::Synthesizer synth(beslam::sim::presetConfig("urban_loop"));
  const auto s = synth.summary();
  EXPECT_GT(s.laps, 1.0);  // the loop closes within the sequence
  double vmin = 1e9, vmax = 0;
  for (int i = 1; i < synth.frameCount(); ++i) {
    const double v =
        (synth.T_world_cam(i).translation() - synth.T_world_cam(i - 1).translation()).norm() * synth.config().rate_hz;
    vmin = std::min(vmin, v), vmax = std::max(vmax, v);
    // Smooth: no jumps in rotation between frames.
    const Eigen::AngleAxisd d(synth.T_world_cam(i - 1).linear().transpose() * synth.T_world_cam(i).linear());
    EXPECT_LT(d.angle(), 5.0 * M_PI / 180.0);
  }
  EXPECT_GT(vmin * 3.6, 15.0);
  EXPECT_LT(vmax * 3.6, 50.0);
  // Camera height above the road stays at the mount height.
  EXPECT_NEAR(synth.T_world_cam(0).translation().norm(), 0.0, 1e-12);
}

// Two processes that need the same synthetic sequence at once (a parallel ablation) both get a complete
// folder, and the one that finishes second does not pull it away from the first (whichever order they
// finish in).
TEST(SynthCache, ConcurrentRendersOfOneSequenceBothSucceed) {
  const std::string cache = tempDir("cache_race");
  SynthConfig c = tinyConfig();
  c.frames = 3;
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    int code = 1;
    try {
      const std::string dir = beslam::sim::ensureSequence(cache, c, "tiny", nullptr);
      code = fs::exists(fs::path(dir) / "COMPLETE") ? 0 : 2;
    } catch (...) {
    }
    ::_exit(code);
  }
  const std::string dir = beslam::sim::ensureSequence(cache, c, "tiny", nullptr);
  // Read the whole folder while the other process may still be finishing.
  size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) files += e.is_regular_file();
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_TRUE(fs::exists(fs::path(dir) / "COMPLETE"));
  EXPECT_GT(files, 3u);
  for (const auto& e : fs::directory_iterator(cache))
    EXPECT_EQ(e.path().filename().string().find(".partial."), std::string::npos) << e.path();
}

TEST(CarMesh, SequencesDrawTheirCarsFromSequenceSizeRange) {
  const beslam::sim::Synthesizer synth(beslam::sim::presetConfig("urban_loop"));
  int cars = 0;
  for (const auto& o : synth.objects()) {
    if (o.shape == "pedestrian") continue;
    int cls = -1;
    for (int c = 0; c < beslam::sim::kCarShapeClasses; ++c)
      if (o.shape == beslam::sim::carShapeName(static_cast<beslam::sim::CarShapeClass>(c))) cls = c;
    ASSERT_GE(cls, 0) << o.shape;
    const auto r = beslam::sim::sequenceSizeRange(static_cast<beslam::sim::CarShapeClass>(cls));
    EXPECT_TRUE(o.length >= r.l_min && o.length <= r.l_max) << o.shape << " l " << o.length;
    EXPECT_TRUE(o.width - 0.008 >= r.w_min - 1e-9 && o.width - 0.008 <= r.w_max + 1e-9) << o.shape << " w " << o.width;
    EXPECT_TRUE(o.height >= r.h_min && o.height <= r.h_max) << o.shape << " h " << o.height;
    ++cars;
  }
  EXPECT_GT(cars, 10);
  // The default profile reproduces the built-in one exactly.
  const auto shape = beslam::sim::CarShapeClass::Wagon;
  const auto profile = beslam::sim::defaultCarProfile(shape);
  const auto a = beslam::sim::carMesh(shape, 4.7, 1.8, 1.5), b = beslam::sim::carMesh(shape, 4.7, 1.8, 1.5, &profile);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]);
  beslam::sim::CarProfile bad = profile;
  bad.x_rf = bad.x_wb + 0.1;
  EXPECT_THROW(beslam::sim::carMesh(shape, 4.7, 1.8, 1.5, &bad), beslam::Error);
}
