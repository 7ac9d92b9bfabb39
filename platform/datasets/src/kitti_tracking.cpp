// KITTI tracking: <root>/{image_02,image_03}/SSSS/NNNNNN.png, velodyne/SSSS/NNNNNN.bin, calib/SSSS.txt,
// label_02/SSSS.txt (optional), oxts/SSSS.txt (not read). Timestamps: frame number * 0.1 s (10 Hz).
// Ground truth only from options.ego_poses (KITTI format, T_world_cam of the chosen camera, one per frame).
// A sequence without an image folder (detections and poses only, like the shared tracking excerpt) is
// accepted when ego_poses is given: one frame per pose row, no images (Frame::gray empty), camera 2 with
// KITTI's usual 1242x375 unless a camera file (options.calibration) says otherwise.
#include <filesystem>

#include "beslam/common/error.hpp"
#include "beslam/datasets/kitti_calib.hpp"
#include "beslam/trajectory/trajectory.hpp"
#include "dataset_impl.hpp"

namespace beslam::datasets::detail {

std::unique_ptr<Dataset> openKittiTracking(const DatasetOptions& options) {
  requireDirectory(options.root, "KITTI tracking root");
  if (options.sequence.empty()) throw Error("dataset options: kitti_tracking needs a sequence (e.g. \"0007\")");
  const std::string calib_path = joinPath(joinPath(options.root, "calib"), options.sequence + ".txt");
  requireFile(calib_path, "calibration file");
  const KittiCalib calib = readObjectCalib(calib_path);

  auto folder_of = [](int i) { return "image_0" + std::to_string(i); };
  auto sequence_images = [&](int i) { return joinPath(joinPath(options.root, folder_of(i)), options.sequence); };
  const bool image_less = !options.ego_poses.empty() && !isDirectory(sequence_images(0)) &&
                          !isDirectory(sequence_images(1)) && !isDirectory(sequence_images(2)) &&
                          !isDirectory(sequence_images(3));
  int cam = 2;
  std::vector<std::pair<std::int64_t, std::string>> images;
  std::string image_dir = options.root;
  if (image_less) {
    const std::size_t rows = trajectory::readKitti(options.ego_poses).size();
    for (std::size_t k = 0; k < rows; ++k) images.emplace_back(static_cast<std::int64_t>(k), std::string());
  } else {
    cam = chooseCamera(
        options.camera, [&](int i) { return isDirectory(sequence_images(i)); },
        [&](int i) { return folder_of(i) + "/" + options.sequence; }, options.root);
    image_dir = sequence_images(cam);
    images = listNumberedFiles(image_dir, ".png", true);
  }
  const std::string velodyne_dir = joinPath(joinPath(options.root, "velodyne"), options.sequence);
  const bool has_lidar = isDirectory(velodyne_dir);
  const std::string label_path = joinPath(joinPath(options.root, "label_02"), options.sequence + ".txt");
  const bool has_labels = isFile(label_path);

  DatasetContents c;
  c.camera_height = kKittiCameraHeight;
  c.frames = selectImageFrames(images, options, image_dir, [&](FrameEntry& f, std::size_t) {
    f.timestamp = 0.1 * static_cast<double>(f.index);
    if (has_lidar) {
      const std::string stem = image_less ? std::to_string(1000000 + f.index).substr(1)
                                          : std::filesystem::path(f.image_path).stem().string();
      f.lidar_path = joinPath(velodyne_dir, stem + ".bin");
    }
    if (has_labels) f.label_path = label_path;
  });
  const auto& P = *calib.P[static_cast<std::size_t>(cam)];
  c.camera = cameraFromProjection(P, 0, 0, calib_path + ": P" + std::to_string(cam));
  if (image_less) {
    c.camera.width = 1242, c.camera.height = 375;
  } else {
    fillImageSize(c.camera, c.frames.front().image_path);
  }
  const std::string camera_text = applyCameraFile(c, options);
  if (has_lidar) c.T_cam_lidar = T_cami_velo(calib, cam);
  if (has_labels) c.label_path = label_path;
  if (!options.ego_poses.empty()) c.ground_truth = selectPoses(options.ego_poses, images.size(), c.frames);
  c.load_color = options.load_color;
  c.load_lidar = options.load_lidar;
  c.description = "KITTI tracking " + options.sequence + " (" + std::to_string(c.frames.size()) + " frames, " +
                  (image_less ? std::string("no images") : folder_of(cam)) + camera_text +
                  rangeText(options, c.frames, images.size()) + (has_lidar ? ", velodyne" : "") +
                  (has_labels ? ", labels" : "") + (options.ego_poses.empty() ? "" : ", poses " + options.ego_poses) +
                  ")";
  return std::make_unique<LoadedDataset>(std::move(c));
}

}  // namespace beslam::datasets::detail
