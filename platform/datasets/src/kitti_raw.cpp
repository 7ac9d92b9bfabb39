// KITTI raw (synced + rectified): <root>/<date>/<date>_drive_NNNN_sync/image_0X/{data/NNNNNNNNNN.png,
// timestamps.txt}, velodyne_points/data/NNNNNNNNNN.bin, and <root>/<date>/calib_cam_to_cam.txt +
// calib_velo_to_cam.txt. <root> may also be the date folder itself. Timestamps ("2011-09-26 13:02:25.964389445")
// become seconds since the sequence's first image. Ground truth only from options.ego_poses (oxts not read).
#include <cstdio>
#include <filesystem>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/datasets/kitti_calib.hpp"
#include "dataset_impl.hpp"
#include "parse_util.hpp"

namespace beslam::datasets::detail {
namespace {

// Days since 1970-01-01 of a proleptic Gregorian date.
std::int64_t daysFromCivil(std::int64_t y, unsigned m, unsigned d) {
  y -= m <= 2;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

}  // namespace

std::vector<long double> readRawTimestamps(const std::string& path) {
  const std::string text = readFile(path);
  std::vector<long double> times;
  const auto lines = splitLines(text);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (isBlank(lines[i])) continue;
    const std::string line(lines[i]);
    int year = 0, month = 0, day = 0, hour = 0, minute = 0, consumed = 0;
    double second = 0;
    if (std::sscanf(line.c_str(), " %4d-%2d-%2d %2d:%2d:%lf %n", &year, &month, &day, &hour, &minute, &second,
                    &consumed) < 6 ||
        static_cast<std::size_t>(consumed) != line.size() || month < 1 || month > 12 || day < 1 || day > 31 ||
        hour < 0 || hour > 23 || minute < 0 || minute > 59 || !(second >= 0 && second < 61))  // NaN too
      throwAt(path, "expected a timestamp like 2011-09-26 13:02:25.964389445, got '" + line + "'",
              static_cast<int>(i + 1));
    // long double keeps sub-microsecond resolution on ~1.3e9 s epoch values before the subtraction.
    const long double seconds =
        static_cast<long double>(daysFromCivil(year, static_cast<unsigned>(month), static_cast<unsigned>(day)) * 86400 +
                                 hour * 3600 + minute * 60) +
        static_cast<long double>(second);
    if (!times.empty() && !(seconds > times.back()))
      throwAt(path,
              "timestamp " + line +
                  " is not after the previous one (timestamps must increase strictly, one line a frame in frame "
                  "order)",
              static_cast<int>(i + 1));
    times.push_back(seconds);
  }
  return times;
}

std::unique_ptr<Dataset> openKittiRaw(const DatasetOptions& options) {
  requireDirectory(options.root, "KITTI raw root");
  if (options.sequence.size() < 10)
    throw Error("dataset options: kitti_raw needs a sequence like \"2011_09_26_drive_0001_sync\", got '" +
                options.sequence + "'");
  const std::string date = options.sequence.substr(0, 10);
  std::string date_dir = joinPath(options.root, date);
  if (!isDirectory(date_dir) && isDirectory(joinPath(options.root, options.sequence))) date_dir = options.root;
  requireDirectory(date_dir, "KITTI raw date");
  const std::string drive_dir = joinPath(date_dir, options.sequence);
  requireDirectory(drive_dir, "KITTI raw drive");
  const std::string cam_to_cam = joinPath(date_dir, "calib_cam_to_cam.txt");
  requireFile(cam_to_cam, "calibration file");
  const KittiCalib calib = readRawCalib(cam_to_cam, joinPath(date_dir, "calib_velo_to_cam.txt"));

  auto folder_of = [](int i) { return "image_0" + std::to_string(i); };
  const int cam = chooseCamera(
      options.camera, [&](int i) { return isDirectory(joinPath(joinPath(drive_dir, folder_of(i)), "data")); },
      [&](int i) { return folder_of(i) + "/data"; }, drive_dir);
  const auto& P = calib.P[static_cast<std::size_t>(cam)];
  if (!P) throwAt(cam_to_cam, "no P_rect_0" + std::to_string(cam) + " for " + folder_of(cam));
  const std::string camera_dir = joinPath(drive_dir, folder_of(cam));
  const std::string image_dir = joinPath(camera_dir, "data");
  const auto images = listNumberedFiles(image_dir, ".png", true);
  const std::string times_path = joinPath(camera_dir, "timestamps.txt");
  requireFile(times_path, "timestamps file");
  const std::vector<long double> times = readRawTimestamps(times_path);
  if (times.size() != images.size())
    throwAt(times_path, "has " + std::to_string(times.size()) + " timestamps but " + image_dir + " has " +
                            std::to_string(images.size()) + " images");

  const std::string velodyne_dir = joinPath(joinPath(drive_dir, "velodyne_points"), "data");
  const bool has_lidar = isDirectory(velodyne_dir);

  DatasetContents c;
  c.camera_height = kKittiCameraHeight;
  c.frames = selectImageFrames(images, options, image_dir, [&](FrameEntry& f, std::size_t p) {
    f.timestamp = static_cast<double>(times[p] - times.front());
    if (has_lidar) f.lidar_path = joinPath(velodyne_dir, std::filesystem::path(f.image_path).stem().string() + ".bin");
  });
  c.camera = cameraFromProjection(*P, 0, 0, cam_to_cam + ": P_rect_0" + std::to_string(cam));
  fillImageSize(c.camera, c.frames.front().image_path);
  const std::string camera_text = applyCameraFile(c, options);
  if (has_lidar) c.T_cam_lidar = T_cami_velo(calib, cam);
  if (!options.ego_poses.empty()) c.ground_truth = selectPoses(options.ego_poses, images.size(), c.frames);
  c.load_color = options.load_color;
  c.load_lidar = options.load_lidar;
  c.description = "KITTI raw " + options.sequence + " (" + std::to_string(c.frames.size()) + " frames, " +
                  folder_of(cam) + camera_text + rangeText(options, c.frames, images.size()) +
                  (has_lidar ? ", velodyne" : "") + (options.ego_poses.empty() ? "" : ", poses " + options.ego_poses) +
                  ")";
  return std::make_unique<LoadedDataset>(std::move(c));
}

}  // namespace beslam::datasets::detail
