// openDataset() and the shared machinery of the layout readers.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/yaml_load.hpp"
#include "beslam/datasets/image_io.hpp"
#include "beslam/datasets/velodyne.hpp"
#include "dataset_impl.hpp"
#include "parse_util.hpp"

namespace beslam::datasets {
namespace detail {

namespace fs = std::filesystem;

Frame LoadedDataset::load(std::size_t i) const {
  if (i >= c_.frames.size())
    throw Error(c_.description + ": frame position " + std::to_string(i) + " out of range (size " +
                std::to_string(c_.frames.size()) + ")");
  const FrameEntry& entry = c_.frames[i];
  Frame frame;
  frame.index = entry.index;
  frame.timestamp = entry.timestamp;
  frame.image_path = entry.image_path;
  frame.lidar_path = entry.lidar_path;
  frame.label_path = entry.label_path;
  if (entry.image_path.empty()) {  // an image-less sequence (tracking data with detections and poses only)
    if (c_.load_lidar && !entry.lidar_path.empty()) frame.lidar_xyzi = readVelodyneBin(entry.lidar_path);
    return frame;
  }
  LoadedImage image = loadImage(entry.image_path, c_.load_color);
  if (image.gray.cols != c_.camera.width || image.gray.rows != c_.camera.height)
    throwAt(entry.image_path, "image is " + std::to_string(image.gray.cols) + "x" + std::to_string(image.gray.rows) +
                                  ", expected " + std::to_string(c_.camera.width) + "x" +
                                  std::to_string(c_.camera.height) + " like the sequence's first image");
  frame.gray = remapped(image.gray, c_.undistort_map1, c_.undistort_map2);
  frame.color = remapped(image.color, c_.undistort_map1, c_.undistort_map2);
  if (c_.load_lidar && !entry.lidar_path.empty()) frame.lidar_xyzi = readVelodyneBin(entry.lidar_path);
  return frame;
}

cv::Mat remapped(const cv::Mat& image, const cv::Mat& map1, const cv::Mat& map2) {
  if (map1.empty() || image.empty()) return image;
  cv::Mat out;
  cv::remap(image, out, map1, map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return out;
}

CameraCalibration requiredCameraFile(const DatasetOptions& options, const std::string& type) {
  if (options.calibration.empty())
    throwAt(options.root, "type " + type +
                              " needs a camera file: set dataset.calibration (model, width, height, fx, fy, cx, cy; "
                              "docs/datasets.md)");
  return readCameraFile(options.calibration);
}

std::vector<double> readTimes(const std::string& path) {
  const std::string text = readFile(path);
  std::vector<double> times;
  const auto lines = splitLines(text);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (isBlank(lines[i])) continue;
    const auto tokens = splitWhitespace(lines[i]);
    double t = 0;
    if (tokens.size() != 1 || !parseDouble(tokens[0], t))
      throwAt(path, "expected one timestamp in seconds, got '" + std::string(lines[i]) + "'", static_cast<int>(i + 1));
    if (!times.empty() && !(t > times.back()))
      throwAt(path,
              "timestamp " + std::string(tokens[0]) +
                  " is not after the previous one (timestamps must increase "
                  "strictly, one line a frame in frame order)",
              static_cast<int>(i + 1));
    times.push_back(t);
  }
  return times;
}

std::string joinPath(const std::string& a, const std::string& b) { return (fs::path(a) / b).string(); }

double kittiCameraHeight(const std::string& sequence_dir) {
  const std::string manifest = joinPath(sequence_dir, "manifest.yaml");
  if (!isFile(manifest)) return kKittiCameraHeight;
  double height = 0;
  try {
    const YAML::Node node = loadYamlFile(manifest)["config"]["camera"]["mount_height"];
    if (node) height = node.as<double>();
  } catch (const YAML::Exception& e) {
    throw Error(manifest + ": cannot read config.camera.mount_height (" + e.what() + ")");
  }
  if (!(height > 0 && height < 100))
    throw Error(manifest + ": config.camera.mount_height is missing or not a positive number of metres");
  return height;
}

bool isDirectory(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

bool isFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

void requireDirectory(const std::string& path, const std::string& what) {
  if (isDirectory(path)) return;
  std::error_code ec;
  if (fs::exists(path, ec)) throwAt(path, "is a file, not a folder (expected the " + what + " folder)");
  throwAt(path, "missing " + what + " folder");
}

void requireFile(const std::string& path, const std::string& what) {
  if (!isFile(path)) throwAt(path, "missing " + what);
}

std::vector<std::pair<std::int64_t, std::string>> listNumberedFiles(const std::string& dir, const std::string& ext,
                                                                    bool contiguous) {
  std::vector<std::pair<std::int64_t, std::string>> files;
  std::size_t digits = 0;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= ext.size() || name.compare(name.size() - ext.size(), ext.size(), ext) != 0) continue;
    const std::string stem = name.substr(0, name.size() - ext.size());
    if (stem.size() > 18 || !std::all_of(stem.begin(), stem.end(), [](char c) { return c >= '0' && c <= '9'; }))
      continue;
    digits = std::max(digits, stem.size());
    files.emplace_back(std::stoll(stem), it->path().string());
  }
  if (ec) throwAt(dir, "cannot list folder: " + ec.message());
  if (files.empty()) throwAt(dir, "no numbered *" + ext + " files");
  std::sort(files.begin(), files.end());
  for (std::size_t i = 1; i < files.size(); ++i)
    if (files[i].first == files[i - 1].first)
      throwAt(files[i].second, "duplicate frame number (also " + files[i - 1].second + ")");
  if (contiguous)
    for (std::size_t i = 0; i < files.size(); ++i)
      if (files[i].first != static_cast<std::int64_t>(i)) {
        char name[64];
        std::snprintf(name, sizeof name, "%0*lld", static_cast<int>(digits), static_cast<long long>(i));
        throwAt(joinPath(dir, name + ext), "missing frame (frame files must be numbered 0, 1, 2, ... without gaps)");
      }
  return files;
}

std::vector<std::size_t> selectFrames(const std::vector<std::int64_t>& indices, const DatasetOptions& options,
                                      const std::string& where) {
  if (options.step < 1) throw Error("dataset options: step must be >= 1 (got " + std::to_string(options.step) + ")");
  if (options.first < 0) throw Error("dataset options: first must be >= 0 (got " + std::to_string(options.first) + ")");
  if (options.last < -1)
    throw Error("dataset options: last must be >= 0 or -1 for the end (got " + std::to_string(options.last) + ")");
  if (options.last != -1 && options.last < options.first)
    throw Error("dataset options: last (" + std::to_string(options.last) + ") < first (" +
                std::to_string(options.first) + ")");
  std::vector<std::size_t> positions;
  for (std::size_t p = 0; p < indices.size(); ++p) {
    const std::int64_t idx = indices[p];
    if (idx < options.first || (options.last != -1 && idx > options.last)) continue;
    if ((idx - options.first) % options.step != 0) continue;
    positions.push_back(p);
  }
  if (positions.empty())
    throwAt(where, "frame range first=" + std::to_string(options.first) + " last=" + std::to_string(options.last) +
                       " step=" + std::to_string(options.step) + " selects none of its " +
                       std::to_string(indices.size()) + " frames (numbers " + std::to_string(indices.front()) + ".." +
                       std::to_string(indices.back()) + ")");
  return positions;
}

std::vector<FrameEntry> selectImageFrames(const std::vector<std::pair<std::int64_t, std::string>>& images,
                                          const DatasetOptions& options, const std::string& where,
                                          const std::function<void(FrameEntry&, std::size_t)>& fill) {
  std::vector<std::int64_t> indices;
  for (const auto& [index, path] : images) indices.push_back(index);
  std::vector<FrameEntry> frames;
  for (std::size_t p : selectFrames(indices, options, where)) {
    FrameEntry f;
    f.index = images[p].first;
    f.image_path = images[p].second;
    fill(f, p);
    frames.push_back(std::move(f));
  }
  return frames;
}

int chooseCamera(const std::string& name, const std::function<bool(int)>& present,
                 const std::function<std::string(int)>& folder_of, const std::string& where) {
  if (name.empty() || name == "auto") {
    for (int i : {0, 2})
      if (present(i)) return i;
    throwAt(where, "missing image folder: neither " + folder_of(0) + " nor " + folder_of(2));
  }
  int index = -1;
  if ((name.size() == 7 || name.size() == 8) && name.compare(0, 6, "image_") == 0) {
    const std::string digits = name.substr(6);
    if (digits == "0" || digits == "00") index = 0;
    if (digits == "1" || digits == "01") index = 1;
    if (digits == "2" || digits == "02") index = 2;
    if (digits == "3" || digits == "03") index = 3;
  }
  if (index < 0)
    throw Error("dataset options: unknown camera '" + name + "' (expected auto, image_0, image_1, image_2 or image_3)");
  if (!present(index)) throwAt(joinPath(where, folder_of(index)), "missing image folder for camera " + name);
  return index;
}

trajectory::Trajectory selectPoses(const std::string& path, std::size_t sequence_frames,
                                   const std::vector<FrameEntry>& frames, const Eigen::Isometry3d& T_left,
                                   const Eigen::Isometry3d& T_right) {
  requireFile(path, "pose file");
  const trajectory::Trajectory all = trajectory::readKitti(path);
  if (all.size() != sequence_frames)
    throwAt(path, "has " + std::to_string(all.size()) + " poses but the sequence has " +
                      std::to_string(sequence_frames) + " frames");
  trajectory::Trajectory selected;
  for (const FrameEntry& f : frames) {
    if (f.index < 0 || static_cast<std::size_t>(f.index) >= all.size())
      throwAt(path, "has no pose for frame " + std::to_string(f.index));
    selected.push_back(f.timestamp, T_left * all.poses[static_cast<std::size_t>(f.index)] * T_right);
  }
  return selected;
}

std::string rangeText(const DatasetOptions& options, const std::vector<FrameEntry>& frames, std::size_t total) {
  if (frames.size() == total) return {};
  std::string text = ", frames " + std::to_string(frames.front().index) + "-" + std::to_string(frames.back().index);
  if (options.step != 1) text += " step " + std::to_string(options.step);
  return text + " of " + std::to_string(total);
}

void fillImageSize(Camera& camera, const std::string& first_image) {
  if (camera.width > 0 && camera.height > 0) return;
  const cv::Size size = readImageSize(first_image);
  camera.width = size.width;
  camera.height = size.height;
}

std::string useCalibration(DatasetContents& c, const CameraCalibration& calibration, const cv::Size& image_size,
                           const std::string& image) {
  const Camera& cam = calibration.camera;
  if (image_size.width != cam.width || image_size.height != cam.height)
    throwAt(calibration.source, "width x height is " + std::to_string(cam.width) + "x" + std::to_string(cam.height) +
                                    " but " + image + " is " + std::to_string(image_size.width) + "x" +
                                    std::to_string(image_size.height) + " (the camera file must describe the images)");
  c.camera = cam;
  c.undistort_map1.release();
  c.undistort_map2.release();
  if (calibration.distorted()) undistortionMaps(calibration, c.undistort_map1, c.undistort_map2);
  if (calibration.height_over_road) c.camera_height = *calibration.height_over_road;
  return ", camera file " + std::filesystem::path(calibration.source).filename().string() + " (" +
         calibration.modelText() + (calibration.distorted() ? ", undistorted" : "") + ")";
}

std::string applyCameraFile(DatasetContents& c, const DatasetOptions& options) {
  if (options.calibration.empty()) return {};
  const CameraCalibration calibration = readCameraFile(options.calibration);
  if (c.frames.empty() || c.frames.front().image_path.empty()) {  // an image-less sequence: nothing to check
    const cv::Size size(calibration.camera.width, calibration.camera.height);
    return useCalibration(c, calibration, size, "the sequence");
  }
  const std::string& first = c.frames.front().image_path;
  return useCalibration(c, calibration, readImageSize(first), first);
}

}  // namespace detail

std::vector<std::string> datasetTypes() {
  return {"kitti_odometry", "kitti_tracking", "kitti_raw", "kitti_object", "tum", "images", "video", "euroc"};
}

std::unique_ptr<Dataset> openDataset(const DatasetOptions& options) {
  if (options.root.empty())
    throw Error("dataset.root is empty: give the dataset's folder (a video: its file), e.g. --set dataset.root=PATH");
  if (options.type == "kitti_odometry") return detail::openKittiOdometry(options);
  if (options.type == "kitti_tracking") return detail::openKittiTracking(options);
  if (options.type == "kitti_raw") return detail::openKittiRaw(options);
  if (options.type == "kitti_object") return detail::openKittiObject(options);
  if (options.type == "tum") return detail::openTum(options);
  if (options.type == "images") return detail::openImageFolder(options);
  if (options.type == "video") return detail::openVideo(options);
  if (options.type == "euroc") return detail::openEuroc(options);
  std::string list;
  for (const auto& t : datasetTypes()) list += (list.empty() ? "" : ", ") + t;
  throw Error("dataset options: unknown dataset type '" + options.type + "' (expected one of " + list + ")");
}

}  // namespace beslam::datasets
