// KITTI tracking: <root>/{image_02,image_03}/SSSS/NNNNNN.png, velodyne/SSSS/NNNNNN.bin, calib/SSSS.txt,
// label_02/SSSS.txt (optional), oxts/SSSS.txt (not read). Timestamps: frame number * 0.1 s (10 Hz).
// Ground truth only from options.ego_poses (KITTI format, T_world_cam of the chosen camera, one per frame).
#include <filesystem>

#include "beslam/common/error.hpp"
#include "beslam/datasets/kitti_calib.hpp"
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
  const int cam = chooseCamera(
      options.camera, [&](int i) { return isDirectory(sequence_images(i)); },
      [&](int i) { return folder_of(i) + "/" + options.sequence; }, options.root);
  const std::string image_dir = sequence_images(cam);
  const auto images = listNumberedFiles(image_dir, ".png", true);
  std::vector<std::int64_t> indices;
  for (const auto& [index, path] : images) indices.push_back(index);

  const std::string velodyne_dir = joinPath(joinPath(options.root, "velodyne"), options.sequence);
  const bool has_lidar = isDirectory(velodyne_dir);
  const std::string label_path = joinPath(joinPath(options.root, "label_02"), options.sequence + ".txt");
  const bool has_labels = isFile(label_path);

  DatasetContents c;
  for (std::size_t p : selectFrames(indices, options, image_dir)) {
    FrameEntry f;
    f.index = images[p].first;
    f.timestamp = 0.1 * static_cast<double>(f.index);
    f.image_path = images[p].second;
    if (has_lidar) f.lidar_path = joinPath(velodyne_dir, std::filesystem::path(f.image_path).stem().string() + ".bin");
    if (has_labels) f.label_path = label_path;
    c.frames.push_back(std::move(f));
  }
  const auto& P = *calib.P[static_cast<std::size_t>(cam)];
  c.camera = options.camera_override ? *options.camera_override
                                     : cameraFromProjection(P, 0, 0, calib_path + ": P" + std::to_string(cam));
  fillImageSize(c.camera, c.frames.front().image_path);
  if (has_lidar) c.T_cam_lidar = T_cami_velo(calib, cam);
  if (has_labels) c.label_path = label_path;
  if (!options.ego_poses.empty()) c.ground_truth = selectPoses(options.ego_poses, images.size(), c.frames);
  c.load_color = options.load_color;
  c.load_lidar = options.load_lidar;
  c.description = "KITTI tracking " + options.sequence + " (" + std::to_string(c.frames.size()) + " frames, " +
                  folder_of(cam) + rangeText(options, c.frames, images.size()) + (has_lidar ? ", velodyne" : "") +
                  (has_labels ? ", labels" : "") + (options.ego_poses.empty() ? "" : ", poses " + options.ego_poses) +
                  ")";
  return std::make_unique<LoadedDataset>(std::move(c));
}

}  // namespace beslam::datasets::detail
