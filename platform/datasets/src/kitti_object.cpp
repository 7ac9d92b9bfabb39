// KITTI object: <root>/{image_2,image_3}/NNNNNN.png, velodyne/NNNNNN.bin, calib/NNNNNN.txt,
// label_2/NNNNNN.txt. Each index file is one independent frame with its own calibration; a dataset holds
// either one frame (sequence "000008") or every index file in range (sequence "") provided they all share
// the same camera and LiDAR calibration. Timestamps: frame number * 0.1 s (the frames are not a sequence).
#include <filesystem>

#include "beslam/common/error.hpp"
#include "beslam/datasets/kitti_calib.hpp"
#include "dataset_impl.hpp"
#include "parse_util.hpp"

namespace beslam::datasets::detail {
namespace {

bool sameCalibration(const Camera& a, const std::optional<Eigen::Isometry3d>& Ta, const Camera& b,
                     const std::optional<Eigen::Isometry3d>& Tb) {
  const double tol = 1e-9;
  if (std::abs(a.fx - b.fx) > tol || std::abs(a.fy - b.fy) > tol || std::abs(a.cx - b.cx) > tol ||
      std::abs(a.cy - b.cy) > tol || Ta.has_value() != Tb.has_value())
    return false;
  return !Ta || (Ta->matrix() - Tb->matrix()).cwiseAbs().maxCoeff() < 1e-9;
}

}  // namespace

std::unique_ptr<Dataset> openKittiObject(const DatasetOptions& options) {
  requireDirectory(options.root, "KITTI object root");
  if (!options.ego_poses.empty()) throw Error("dataset options: ego_poses is not supported for kitti_object");
  auto folder_of = [](int i) { return "image_" + std::to_string(i); };
  const int cam = chooseCamera(
      options.camera, [&](int i) { return isDirectory(joinPath(options.root, folder_of(i))); }, folder_of,
      options.root);
  const std::string image_dir = joinPath(options.root, folder_of(cam));

  std::vector<std::pair<std::int64_t, std::string>> images;
  if (options.sequence.empty()) {
    images = listNumberedFiles(image_dir, ".png", false);
  } else {
    std::int64_t index = 0;
    if (!parseInt(options.sequence, index) || index < 0)
      throw Error("dataset options: kitti_object sequence must be a frame number like \"000008\" or empty, got '" +
                  options.sequence + "'");
    const std::string path = joinPath(image_dir, options.sequence + ".png");
    requireFile(path, "image");
    images.emplace_back(index, path);
  }
  const std::string velodyne_dir = joinPath(options.root, "velodyne");
  const bool has_lidar = isDirectory(velodyne_dir);
  DatasetContents c;
  c.camera_height = kKittiCameraHeight;
  std::string first_calib;  // the first frame's calibration file, which the others' must agree with
  c.frames = selectImageFrames(images, options, image_dir, [&](FrameEntry& f, std::size_t) {
    f.timestamp = 0.1 * static_cast<double>(f.index);
    const std::string stem = std::filesystem::path(f.image_path).stem().string();
    if (has_lidar) f.lidar_path = joinPath(velodyne_dir, stem + ".bin");
    const std::string label_path = joinPath(joinPath(options.root, "label_2"), stem + ".txt");
    if (isFile(label_path)) f.label_path = label_path;

    const std::string calib_path = joinPath(joinPath(options.root, "calib"), stem + ".txt");
    requireFile(calib_path, "calibration file");
    const KittiCalib calib = readObjectCalib(calib_path);
    const Camera camera =
        cameraFromProjection(*calib.P[static_cast<std::size_t>(cam)], 0, 0, calib_path + ": P" + std::to_string(cam));
    const auto T_cam_lidar = has_lidar ? T_cami_velo(calib, cam) : std::nullopt;
    if (first_calib.empty()) {
      c.camera = camera;
      c.T_cam_lidar = T_cam_lidar;
      first_calib = calib_path;
    } else if (!sameCalibration(c.camera, c.T_cam_lidar, camera, T_cam_lidar)) {
      throwAt(calib_path, "calibration differs from " + first_calib + "; open such frames one at a time (sequence: \"" +
                              stem + "\")");
    }
  });
  fillImageSize(c.camera, c.frames.front().image_path);
  const std::string camera_text = applyCameraFile(c, options);
  if (c.frames.size() == 1) c.label_path = c.frames.front().label_path;
  c.load_color = options.load_color;
  c.load_lidar = options.load_lidar;
  c.description = "KITTI object " + (options.sequence.empty() ? std::string("training") : options.sequence) + " (" +
                  std::to_string(c.frames.size()) + (c.frames.size() == 1 ? " frame, " : " frames, ") + folder_of(cam) +
                  camera_text + rangeText(options, c.frames, images.size()) + (has_lidar ? ", velodyne" : "") + ")";
  return std::make_unique<LoadedDataset>(std::move(c));
}

}  // namespace beslam::datasets::detail
