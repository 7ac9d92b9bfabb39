// KITTI odometry: <root>/sequences/NN/{image_0..image_3, velodyne}/NNNNNN.{png,bin}, calib.txt, times.txt;
// <root>/poses/NN.txt (optional ground truth: T_world_cam0, world = camera 0 at frame 0).
#include <filesystem>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/datasets/kitti_calib.hpp"
#include "dataset_impl.hpp"
#include "parse_util.hpp"

namespace beslam::datasets::detail {

std::unique_ptr<Dataset> openKittiOdometry(const DatasetOptions& options) {
  requireDirectory(options.root, "KITTI odometry root");
  if (options.sequence.empty()) throw Error("dataset options: kitti_odometry needs a sequence (e.g. \"06\")");
  const std::string sequence_dir = joinPath(joinPath(options.root, "sequences"), options.sequence);
  requireDirectory(sequence_dir, "KITTI odometry sequence");
  const std::string calib_path = joinPath(sequence_dir, "calib.txt");
  requireFile(calib_path, "calibration file");
  const KittiCalib calib = readOdometryCalib(calib_path);

  auto folder_of = [](int i) { return "image_" + std::to_string(i); };
  const int cam = chooseCamera(
      options.camera, [&](int i) { return isDirectory(joinPath(sequence_dir, folder_of(i))); }, folder_of,
      sequence_dir);
  const auto& P = calib.P[static_cast<std::size_t>(cam)];
  if (!P) throwAt(calib_path, "no P" + std::to_string(cam) + " for " + folder_of(cam));

  const std::string image_dir = joinPath(sequence_dir, folder_of(cam));
  const auto images = listNumberedFiles(image_dir, ".png", true);
  const std::string times_path = joinPath(sequence_dir, "times.txt");
  requireFile(times_path, "timestamps file");
  const std::vector<double> times = readTimes(times_path);
  if (times.size() != images.size())
    throwAt(times_path, "has " + std::to_string(times.size()) + " timestamps but " + image_dir + " has " +
                            std::to_string(images.size()) + " images");

  const std::string velodyne_dir = joinPath(sequence_dir, "velodyne");
  const bool has_lidar = isDirectory(velodyne_dir);

  DatasetContents c;
  c.camera_height = kittiCameraHeight(sequence_dir);
  c.frames = selectImageFrames(images, options, image_dir, [&](FrameEntry& f, std::size_t p) {
    f.timestamp = times[p];
    if (has_lidar) f.lidar_path = joinPath(velodyne_dir, std::filesystem::path(f.image_path).stem().string() + ".bin");
  });
  c.camera = cameraFromProjection(*P, 0, 0, calib_path + ": P" + std::to_string(cam));
  fillImageSize(c.camera, c.frames.front().image_path);
  const std::string camera_text = applyCameraFile(c, options);
  if (has_lidar) c.T_cam_lidar = T_cami_velo(calib, cam);
  c.load_color = options.load_color;
  c.load_lidar = options.load_lidar;

  // Ground truth: poses/NN.txt are T_world_cam0 (rectified camera 0); for camera i,
  // T_world'_cami = T_cami_cam0 * T_world_cam0 * T_cam0_cami with world' = camera i at frame 0.
  std::string gt_text;
  if (!options.ego_poses.empty()) {
    c.ground_truth = selectPoses(options.ego_poses, images.size(), c.frames);
    gt_text = ", poses " + options.ego_poses;
  } else {
    const std::string poses_path = joinPath(joinPath(options.root, "poses"), options.sequence + ".txt");
    if (isFile(poses_path)) {
      const Eigen::Isometry3d T_cami_cam0 = T_cami_rect0(*P);
      c.ground_truth = selectPoses(poses_path, images.size(), c.frames, T_cami_cam0, T_cami_cam0.inverse());
      gt_text = ", ground truth";
    }
  }
  c.description = (options.name.empty() ? "KITTI odometry " + options.sequence : options.name) + " (" +
                  std::to_string(c.frames.size()) + " frames, " + folder_of(cam) + camera_text +
                  rangeText(options, c.frames, images.size()) + (has_lidar ? ", velodyne" : "") + gt_text + ")";
  return std::make_unique<LoadedDataset>(std::move(c));
}

}  // namespace beslam::datasets::detail
