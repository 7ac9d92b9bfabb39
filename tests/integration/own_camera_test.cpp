// Your own camera, end to end (docs/datasets.md): `beslam synth` renders a short static drive (100 frames,
// 80 m); the test writes its frames as a folder of images distorted with a known radial-tangential model
// plus a camera file, as an EuRoC/ASL folder and as an MJPG video, and runs `beslam run` with backend_orb on
// each, five backend seeds for the folder:
// - the host's undistortion is exact: a control folder, made by undistorting the distorted images with
//   OpenCV's own maps and run as a pinhole camera, gives the distorted route's APE to the last digit on every
//   seed (so the camera file's model, its maps and their use are right);
// - the distorted folder tracks every frame, and the median of its Sim(3) APE stays under twice the median
//   on the undistorted images, while the same images with the distortion left out of the camera file end at
//   least 10 times further from the truth;
// - the EuRoC folder (sensor.yaml's camera, ground truth through T_BS) gives the distorted folder's APE within
//   5 %; the video tracks.
// Ground truth reaches the runs through dataset.ego_poses. Seeded backend; nothing depends on the machine's speed.
//
// Why "under twice" and not "within 5 %": on this rendered drive the APE is governed by how the images were
// resampled, not by the camera model. Twenty seeds (BESLAM_OWN_CAMERA_SEEDS=12-31) put the distorted route
// 22 % above the undistorted one; making the distorted images with a Lanczos kernel instead of a bilinear one
// moves that to +91 %, and undistorting those with a bicubic kernel to -43 % (docs/notes, the distortion
// study). The renderer's blur is raised to 1 px: with its default 0.4 px the rendered edges alias.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>

namespace fs = std::filesystem;

namespace {

constexpr int kFrames = 100;  // the static loop's first 80 m: enough for backend_orb to initialise and map
// Fresh seeds (earlier tolerances were set looking at seeds 1-6); BESLAM_OWN_CAMERA_SEEDS=12-31 measures others.
std::vector<int> seeds() {
  const char* env = std::getenv("BESLAM_OWN_CAMERA_SEEDS");
  if (!env) return {7, 8, 9, 10, 11};
  int first = 0, last = 0;
  if (std::sscanf(env, "%d-%d", &first, &last) != 2 || last < first) {
    ADD_FAILURE() << "BESLAM_OWN_CAMERA_SEEDS: expected FIRST-LAST, got '" << env << "'";
    return {7};
  }
  std::vector<int> out;
  for (int s = first; s <= last; ++s) out.push_back(s);
  return out;
}
const std::vector<int> kSeeds = seeds();
const cv::Matx33d kK(718.856, 0, 607.1928, 0, 718.856, 185.2157, 0, 0, 1);  // beslam synth's default camera
const std::vector<double> kD = {-0.2, 0.05, 0.001, -0.0005, 0.0};           // k1 k2 p1 p2 k3

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int run(const std::string& args, const fs::path& log) {
  const std::string cmd =
      std::string(BESLAM_BINARY_DIR) + "/bin/beslam " + args + " > " + log.string() + " 2>&1 < /dev/null";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The image the distorted camera would have taken of the pinhole image: each distorted pixel samples the
// pinhole image at its undistorted position (cv::undistortPoints).
cv::Mat distortionMap(cv::Size size) {
  std::vector<cv::Point2f> pixels, ideal;
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) pixels.emplace_back(static_cast<float>(x), static_cast<float>(y));
  cv::undistortPoints(pixels, ideal, kK, kD, cv::noArray(), kK);
  cv::Mat map(size, CV_32FC2);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      const cv::Point2f& p = ideal[static_cast<std::size_t>(y * size.width + x)];
      map.at<cv::Vec2f>(y, x) = cv::Vec2f(p.x, p.y);
    }
  return map;
}

std::string cameraFile(bool distorted, int width = 1241) {
  std::ostringstream ss;
  ss.precision(10);
  ss << "model: pinhole\nwidth: " << width << "\nheight: 376\nfx: " << kK(0, 0) << "\nfy: " << kK(1, 1)
     << "\ncx: " << kK(0, 2) << "\ncy: " << kK(1, 2) << "\nfps: 10\nheight_over_road: 1.65\n";
  if (distorted)
    ss << "distortion: [" << kD[0] << ", " << kD[1] << ", " << kD[2] << ", " << kD[3] << ", " << kD[4] << "]\n";
  return ss.str();
}

// The rendered ground truth (KITTI pose file: T_world_cam, 3x4 row-major per frame).
std::vector<Eigen::Isometry3d> readKittiPoses(const fs::path& path) {
  std::vector<Eigen::Isometry3d> poses;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::istringstream ss(line);
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    for (int k = 0; k < 12; ++k) ss >> M(k / 4, k % 4);
    if (ss) poses.emplace_back(M);
  }
  return poses;
}

// The same distorted frames as an EuRoC/ASL folder: cam0/data.csv, cam0/data/<ns>.png, cam0/sensor.yaml
// (4 radial-tangential coefficients, a body-to-camera T_BS), and the body's ground truth
// T_world_body = T_world_cam * T_BS^-1 in state_groundtruth_estimate0/data.csv.
void writeEuroc(const fs::path& dir, const fs::path& distorted, const std::vector<Eigen::Isometry3d>& T_world_cam) {
  const fs::path cam = dir / "euroc/mav0/cam0";
  fs::create_directories(cam / "data");
  fs::create_directories(dir / "euroc/mav0/state_groundtruth_estimate0");
  Eigen::Isometry3d T_BS = Eigen::Isometry3d::Identity();
  T_BS.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T_BS.translation() = Eigen::Vector3d(-0.02, 0.07, 0.01);
  std::ofstream csv(cam / "data.csv"), gt(dir / "euroc/mav0/state_groundtruth_estimate0/data.csv");
  csv << "#timestamp [ns],filename\n";
  gt << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n";
  gt.precision(17);
  for (std::size_t i = 0; i < T_world_cam.size(); ++i) {
    const std::string stamp = std::to_string(1403636579763555584LL + 100000000LL * static_cast<long long>(i));
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.png", i);
    fs::copy_file(distorted / name, cam / "data" / (stamp + ".png"));
    csv << stamp << "," << stamp << ".png\n";
    const Eigen::Isometry3d T_world_body = T_world_cam[i] * T_BS.inverse();
    const Eigen::Quaterniond q(T_world_body.linear());
    const Eigen::Vector3d p = T_world_body.translation();
    gt << stamp << "," << p.x() << "," << p.y() << "," << p.z() << "," << q.w() << "," << q.x() << "," << q.y() << ","
       << q.z() << "\n";
  }
  std::ofstream sensor(cam / "sensor.yaml");
  sensor.precision(17);
  sensor << "%YAML:1.0\nsensor_type: camera\ncomment: rendered by beslam synth\nT_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int k = 0; k < 16; ++k) sensor << (k ? ", " : "") << T_BS.matrix()(k / 4, k % 4);
  sensor << "]\nrate_hz: 10\nresolution: [1241, 376]\ncamera_model: pinhole\nintrinsics: [" << kK(0, 0) << ", "
         << kK(1, 1) << ", " << kK(0, 2) << ", " << kK(1, 2) << "]\ndistortion_model: radial-tangential\n"
         << "distortion_coefficients: [" << kD[0] << ", " << kD[1] << ", " << kD[2] << ", " << kD[3] << "]\n";
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

struct RunResult {
  int tracked = -1;
  double sim3 = -1;
  std::string summary;
};

RunResult runOn(const fs::path& dir, const std::string& name, const std::string& sets, int seed = 7) {
  const fs::path out = dir / name;
  const int code = run("run " + (dir / "pipeline.yaml").string() + " " + sets +
                           " --set backend.seed=" + std::to_string(seed) + " --out " + out.string(),
                       dir / (name + ".log"));
  RunResult r;
  EXPECT_EQ(code, 0) << name << ": " << slurp(dir / (name + ".log"));
  if (code != 0) return r;
  r.summary = slurp(out / "summary.json");
  const nlohmann::json j = nlohmann::json::parse(r.summary);
  r.tracked = j["tracked"].get<int>();
  if (j.contains("ape_sim3") || r.summary.find("\"sim3_rmse\"") != std::string::npos) {
    const std::size_t at = r.summary.find("\"sim3_rmse\":");
    r.sim3 = std::stod(r.summary.substr(at + 12));
  }
  return r;
}

TEST(OwnCamera, DistortedFolderWithCameraFileMatchesTheUndistortedRunAndAVideoTracks) {
  const fs::path dir = fs::temp_directory_path() / ("beslam_own_camera_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  ASSERT_EQ(
      run("synth --config static_loop --out " + (dir / "synth").string() + " --set frames=" + std::to_string(kFrames) +
              " --set lidar.enabled=false --set camera.colour=false --set image.blur_sigma=1.0",
          dir / "synth.log"),
      0)
      << slurp(dir / "synth.log");
  const fs::path images = dir / "synth/sequences/00/image_0";

  // The distorted folder (times.txt beside the images), the control (the distorted images undistorted with
  // OpenCV's own maps, as the host does, saved as a pinhole folder) and an MJPG video of the undistorted frames.
  fs::create_directories(dir / "distorted");
  fs::create_directories(dir / "resampled");
  fs::copy_file(dir / "synth/sequences/00/times.txt", dir / "distorted/times.txt");
  fs::copy_file(dir / "synth/sequences/00/times.txt", dir / "resampled/times.txt");
  cv::Mat map, undistort1, undistort2;
  // (MJPG frames have an even width: the video keeps the first 1240 columns, the principal point stays.)
  cv::VideoWriter video((dir / "drive.avi").string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0,
                        cv::Size(1240, 376), false);
  for (int i = 0; i < kFrames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    const cv::Mat pinhole = cv::imread((images / name).string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(pinhole.empty()) << images / name;
    if (map.empty()) {
      map = distortionMap(pinhole.size());
      cv::initUndistortRectifyMap(kK, kD, cv::noArray(), kK, pinhole.size(), CV_16SC2, undistort1, undistort2);
    }
    cv::Mat distorted, resampled;
    cv::remap(pinhole, distorted, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::remap(distorted, resampled, undistort1, undistort2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    ASSERT_TRUE(cv::imwrite((dir / "distorted" / name).string(), distorted));
    ASSERT_TRUE(cv::imwrite((dir / "resampled" / name).string(), resampled));
    if (video.isOpened()) video.write(pinhole(cv::Rect(0, 0, 1240, 376)).clone());
  }
  const bool have_video = video.isOpened();
  video.release();
  std::ofstream(dir / "pinhole.yaml") << cameraFile(false);
  std::ofstream(dir / "distorted.yaml") << cameraFile(true);
  std::ofstream(dir / "video.yaml") << cameraFile(false, 1240);
  std::ofstream(dir / "pipeline.yaml") << "dataset: {type: images}\n"
                                       << "backend: {plugin: backend_orb, features: 3000}\n"
                                       << "output: {samples: 0}\n";
  const std::string poses = " --set dataset.ego_poses=" + (dir / "synth/poses/00.txt").string();
  const std::string pinhole_sets = " --set dataset.calibration=" + (dir / "pinhole.yaml").string() + poses;
  const std::string distorted_sets = "--set dataset.root=" + (dir / "distorted").string() +
                                     " --set dataset.calibration=" + (dir / "distorted.yaml").string() + poses;

  // Per seed: the rendered (undistorted) images, the distorted folder with its camera file, the control.
  std::vector<double> ref_ape, dis_ape;
  RunResult dis;  // the first seed's distorted run, for the EuRoC comparison below
  for (const int seed : kSeeds) {
    const std::string tag = "_seed" + std::to_string(seed);
    const RunResult r = runOn(dir, "undistorted" + tag, "--set dataset.root=" + images.string() + pinhole_sets, seed);
    const RunResult d = runOn(dir, "distorted" + tag, distorted_sets, seed);
    const RunResult c =
        runOn(dir, "resampled" + tag, "--set dataset.root=" + (dir / "resampled").string() + pinhole_sets, seed);
    EXPECT_EQ(r.tracked, kFrames) << r.summary;
    EXPECT_EQ(d.tracked, kFrames) << d.summary;
    ASSERT_GT(r.sim3, 0) << r.summary;
    ASSERT_GT(d.sim3, 0) << d.summary;
    // The host's undistortion is OpenCV's: the control is the same run.
    EXPECT_EQ(c.sim3, d.sim3) << "seed " << seed << ": " << c.summary;
    std::printf(
        "[ own camera ] seed %d: Sim(3) APE undistorted %.4f m, distorted + camera file %.4f m (%+.1f %%), "
        "the control %.4f m\n",
        seed, r.sim3, d.sim3, 100.0 * (d.sim3 - r.sim3) / r.sim3, c.sim3);
    ref_ape.push_back(r.sim3);
    dis_ape.push_back(d.sim3);
    if (seed == kSeeds.front()) dis = d;
  }
  const double ref_median = median(ref_ape), dis_median = median(dis_ape);
  std::printf(
      "[ own camera ] medians of %zu seeds: undistorted %.4f m (%.4f-%.4f), distorted %.4f m (%.4f-%.4f), "
      "%+.1f %%\n",
      kSeeds.size(), ref_median, *std::min_element(ref_ape.begin(), ref_ape.end()),
      *std::max_element(ref_ape.begin(), ref_ape.end()), dis_median, *std::min_element(dis_ape.begin(), dis_ape.end()),
      *std::max_element(dis_ape.begin(), dis_ape.end()), 100.0 * (dis_median - ref_median) / ref_median);
  EXPECT_LT(dis_median, 2 * ref_median) << "undistorted " << ref_median << " m, distorted " << dis_median << " m";

  const RunResult ignored = runOn(dir, "distortion_ignored",
                                  "--set dataset.root=" + (dir / "distorted").string() + pinhole_sets, kSeeds.front());
  std::printf("[ own camera ] distortion left out of the camera file: %.4f m\n", ignored.sim3);
  EXPECT_GT(ignored.sim3, 10 * ref_median) << "the distortion matters: without it the run should be far off";
  EXPECT_NE(dis.summary.find("camera file distorted.yaml (pinhole, radial-tangential, undistorted)"), std::string::npos)
      << dis.summary;

  // The EuRoC route: the same images and camera, sensor.yaml's camera, ground truth through T_BS. Only the
  // timestamps (absolute, from data.csv) and the ground truth's route differ from the distorted folder's run.
  writeEuroc(dir, dir / "distorted", readKittiPoses(dir / "synth/poses/00.txt"));
  const RunResult euroc =
      runOn(dir, "euroc", "--set dataset.type=euroc --set dataset.root=" + (dir / "euroc").string(), kSeeds.front());
  std::printf("[ own camera ] EuRoC layout: %d of %d frames tracked, Sim(3) APE %.4f m\n", euroc.tracked, kFrames,
              euroc.sim3);
  EXPECT_EQ(euroc.tracked, kFrames) << euroc.summary;
  EXPECT_LT(std::abs(euroc.sim3 - dis.sim3), 0.05 * dis.sim3) << euroc.summary;
  EXPECT_NE(euroc.summary.find("ground truth for 100/100 frames"), std::string::npos) << euroc.summary;

  if (!have_video) {
    std::printf("[ own camera ] skipped the video run: this OpenCV cannot write MJPG into .avi\n");
  } else {
    const RunResult vid = runOn(dir, "video",
                                "--set dataset.type=video --set dataset.root=" + (dir / "drive.avi").string() +
                                    " --set dataset.calibration=" + (dir / "video.yaml").string() + poses,
                                kSeeds.front());
    std::printf("[ own camera ] video: %d of %d frames tracked, Sim(3) APE %.4f m\n", vid.tracked, kFrames, vid.sim3);
    EXPECT_GE(vid.tracked, kFrames * 9 / 10) << vid.summary;
    EXPECT_GT(vid.sim3, 0) << vid.summary;
    EXPECT_LT(vid.sim3, 2 * ref_median + 0.05) << vid.summary;
  }
  if (HasFailure())
    std::printf("[ own camera ] the data and runs stay in %s\n", dir.c_str());
  else
    fs::remove_all(dir);
}

}  // namespace
