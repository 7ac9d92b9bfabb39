// Your own camera, end to end (docs/datasets.md): `beslam synth` renders a short static drive (100 frames,
// 80 m); the test writes its frames as a folder of images distorted with a known radial-tangential model
// plus a camera file, as an EuRoC/ASL folder and as an MJPG video. `beslam run` with backend_orb on the distorted
// folder (undistorted by the host with the camera file) must track every frame with a Sim(3) APE within 15 % of the
// same run on the undistorted images, while the same distorted images with the distortion left out of the camera file
// end at least 10 times further from the truth; the EuRoC folder (sensor.yaml's camera, ground truth through T_BS) must
// give the distorted folder's APE within 5 %, and the video must track too. Ground truth reaches the other runs through
// dataset.ego_poses. Seeded backend; the outcome does not depend on the machine's speed.
//
// Why 15 % and not the 5 %: on this drive the reference run's own APE moves by up to 25 % with the
// backend's seed alone (0.028 to 0.036 m over seeds 1-6), and the distorted camera sees its periphery up to
// 13 % more coarsely (k1 = -0.2) before the host resamples it: over seeds 1-6 the distorted route measured
// 0.036 to 0.037 m against 0.028 to 0.036 m (seed 1: 0.0375 against 0.0342 m, +9.6 %). Leaving the
// distortion out of the camera file gives some 4 m. The renderer's blur is raised to 1 px: with its default
// 0.4 px the rendered edges alias, and the resampling of the distorted route alone halves the APE.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
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

struct RunResult {
  int tracked = -1;
  double sim3 = -1;
  std::string summary;
};

RunResult runOn(const fs::path& dir, const std::string& name, const std::string& sets) {
  const fs::path out = dir / name;
  const int code =
      run("run " + (dir / "pipeline.yaml").string() + " " + sets + " --out " + out.string(), dir / (name + ".log"));
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

  // The distorted folder (times.txt beside the images) and an MJPG video of the undistorted frames.
  fs::create_directories(dir / "distorted");
  fs::copy_file(dir / "synth/sequences/00/times.txt", dir / "distorted/times.txt");
  cv::Mat map;
  // (MJPG frames have an even width: the video keeps the first 1240 columns, the principal point stays.)
  cv::VideoWriter video((dir / "drive.avi").string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0,
                        cv::Size(1240, 376), false);
  for (int i = 0; i < kFrames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    const cv::Mat pinhole = cv::imread((images / name).string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(pinhole.empty()) << images / name;
    if (map.empty()) map = distortionMap(pinhole.size());
    cv::Mat distorted;
    cv::remap(pinhole, distorted, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    ASSERT_TRUE(cv::imwrite((dir / "distorted" / name).string(), distorted));
    if (video.isOpened()) video.write(pinhole(cv::Rect(0, 0, 1240, 376)).clone());
  }
  const bool have_video = video.isOpened();
  video.release();
  std::ofstream(dir / "pinhole.yaml") << cameraFile(false);
  std::ofstream(dir / "distorted.yaml") << cameraFile(true);
  std::ofstream(dir / "video.yaml") << cameraFile(false, 1240);
  std::ofstream(dir / "pipeline.yaml") << "dataset: {type: images}\n"
                                       << "backend: {plugin: backend_orb, features: 3000, seed: 1}\n"
                                       << "output: {samples: 0}\n";
  const std::string poses = " --set dataset.ego_poses=" + (dir / "synth/poses/00.txt").string();

  // The reference: the rendered (undistorted) images, timestamps from the camera file's fps.
  const RunResult ref = runOn(dir, "undistorted",
                              "--set dataset.root=" + images.string() +
                                  " --set dataset.calibration=" + (dir / "pinhole.yaml").string() + poses);
  const RunResult dis = runOn(dir, "distorted",
                              "--set dataset.root=" + (dir / "distorted").string() +
                                  " --set dataset.calibration=" + (dir / "distorted.yaml").string() + poses);
  const RunResult ignored = runOn(dir, "distortion_ignored",
                                  "--set dataset.root=" + (dir / "distorted").string() +
                                      " --set dataset.calibration=" + (dir / "pinhole.yaml").string() + poses);
  EXPECT_EQ(ref.tracked, kFrames) << ref.summary;
  EXPECT_EQ(dis.tracked, kFrames) << dis.summary;
  ASSERT_GT(ref.sim3, 0) << ref.summary;
  ASSERT_GT(dis.sim3, 0) << dis.summary;
  std::printf(
      "[ own camera ] Sim(3) APE undistorted %.4f m, distorted + camera file %.4f m (%+.1f %%), distortion "
      "ignored %.4f m\n",
      ref.sim3, dis.sim3, 100.0 * (dis.sim3 - ref.sim3) / ref.sim3, ignored.sim3);
  EXPECT_LT(std::abs(dis.sim3 - ref.sim3), 0.15 * ref.sim3)
      << "undistorted " << ref.sim3 << " m, distorted " << dis.sim3 << " m";
  EXPECT_GT(ignored.sim3, 10 * ref.sim3) << "the distortion matters: without it the run should be far off";
  EXPECT_NE(dis.summary.find("camera file distorted.yaml (pinhole, radial-tangential, undistorted)"), std::string::npos)
      << dis.summary;

  // The EuRoC route: the same images and camera, sensor.yaml's camera, ground truth through T_BS. Only the
  // timestamps (absolute, from data.csv) and the ground truth's route differ from the distorted folder's run.
  writeEuroc(dir, dir / "distorted", readKittiPoses(dir / "synth/poses/00.txt"));
  const RunResult euroc =
      runOn(dir, "euroc", "--set dataset.type=euroc --set dataset.root=" + (dir / "euroc").string());
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
                                    " --set dataset.calibration=" + (dir / "video.yaml").string() + poses);
    std::printf("[ own camera ] video: %d of %d frames tracked, Sim(3) APE %.4f m\n", vid.tracked, kFrames, vid.sim3);
    EXPECT_GE(vid.tracked, kFrames * 9 / 10) << vid.summary;
    EXPECT_GT(vid.sim3, 0) << vid.summary;
    EXPECT_LT(vid.sim3, 2 * ref.sim3 + 0.05) << vid.summary;
  }
  if (HasFailure())
    std::printf("[ own camera ] the data and runs stay in %s\n", dir.c_str());
  else
    fs::remove_all(dir);
}

}  // namespace
