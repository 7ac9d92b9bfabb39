// TUM RGB-D: <root>/rgb.txt ("timestamp rgb/NNN.png", '#' comments), the listed images, and an optional
// groundtruth.txt ("t tx ty tz qx qy qz qw", T_world_cam of the colour camera's optical frame).
#include "beslam/datasets/tum.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <numeric>
#include <opencv2/calib3d.hpp>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/datasets/image_io.hpp"
#include "dataset_impl.hpp"
#include "parse_util.hpp"

namespace beslam::datasets {

std::optional<TumIntrinsics> tumDefaultIntrinsics(const std::string& folder_name) {
  std::string name = folder_name;
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  auto has = [&](const char* a, const char* b) {
    return name.find(a) != std::string::npos || name.find(b) != std::string::npos;
  };
  // Published colour-camera calibration of the TUM RGB-D benchmark (Sturm et al. 2012).
  if (has("freiburg1", "fr1"))
    return TumIntrinsics{"fr1", {640, 480, 517.3, 516.5, 318.6, 255.3}, {0.2624, -0.9531, -0.0054, 0.0026, 1.1633}};
  if (has("freiburg2", "fr2"))
    return TumIntrinsics{"fr2", {640, 480, 520.9, 521.0, 325.1, 249.7}, {0.2312, -0.7849, -0.0033, -0.0001, 0.9172}};
  if (has("freiburg3", "fr3")) return TumIntrinsics{"fr3", {640, 480, 535.4, 539.2, 320.1, 247.6}, {0, 0, 0, 0, 0}};
  return std::nullopt;
}

std::optional<Eigen::Isometry3d> poseAt(const trajectory::Trajectory& trajectory, double stamp, double max_dt,
                                        double max_gap) {
  const auto& stamps = trajectory.stamps;
  if (stamps.empty()) return std::nullopt;
  const std::size_t b =
      static_cast<std::size_t>(std::lower_bound(stamps.begin(), stamps.end(), stamp) - stamps.begin());
  if (b < stamps.size() && b > 0 && stamps[b] - stamps[b - 1] <= max_gap) {
    const double span = stamps[b] - stamps[b - 1];
    const double w = span > 0 ? (stamp - stamps[b - 1]) / span : 0.0;
    const Eigen::Isometry3d& A = trajectory.poses[b - 1];
    const Eigen::Isometry3d& B = trajectory.poses[b];
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(A.linear()).slerp(w, Eigen::Quaterniond(B.linear())).toRotationMatrix();
    T.translation() = (1 - w) * A.translation() + w * B.translation();
    return T;
  }
  std::optional<std::size_t> best;
  for (std::size_t k : {b - 1, b})  // b - 1 wraps when b == 0 and is then skipped
    if (k < stamps.size() && std::abs(stamps[k] - stamp) <= max_dt &&
        (!best || std::abs(stamps[k] - stamp) < std::abs(stamps[*best] - stamp)))
      best = k;
  if (!best) return std::nullopt;
  return trajectory.poses[*best];
}

namespace detail {

std::unique_ptr<Dataset> openTum(const DatasetOptions& options) {
  requireDirectory(options.root, "TUM RGB-D sequence");
  if (!options.ego_poses.empty())
    throw Error("dataset options: ego_poses is not supported for tum (groundtruth.txt is read from the folder)");
  const std::string rgb_list = joinPath(options.root, "rgb.txt");
  requireFile(rgb_list, "image list rgb.txt");
  const std::string text = readFile(rgb_list);
  std::vector<FrameEntry> all;
  const auto lines = splitLines(text);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (isBlank(lines[i]) || splitWhitespace(lines[i]).front().front() == '#') continue;
    const int line_no = static_cast<int>(i + 1);
    const auto tokens = splitWhitespace(lines[i]);
    double stamp = 0;
    if (tokens.size() != 2)
      throwAt(rgb_list, "expected 'timestamp path', got '" + std::string(lines[i]) + "'", line_no);
    if (!parseDouble(tokens[0], stamp))
      throwAt(rgb_list, "'" + std::string(tokens[0]) + "' is not a timestamp", line_no);
    if (!all.empty() && stamp <= all.back().timestamp) throwAt(rgb_list, "timestamps are not increasing", line_no);
    FrameEntry f;
    f.index = static_cast<std::int64_t>(all.size());
    f.timestamp = stamp;
    f.image_path = joinPath(options.root, std::string(tokens[1]));
    all.push_back(std::move(f));
  }
  if (all.empty()) throwAt(rgb_list, "lists no images");
  std::vector<std::int64_t> indices(all.size());
  std::iota(indices.begin(), indices.end(), 0);

  DatasetContents c;
  for (std::size_t p : selectFrames(indices, options, rgb_list)) {
    requireFile(all[p].image_path, "image (listed in " + rgb_list + ")");
    c.frames.push_back(all[p]);
  }

  // The sequence folder's own name ("rgbd_dataset_freiburg1_xyz"), also for "." or a trailing slash.
  std::filesystem::path normal = std::filesystem::absolute(options.root).lexically_normal();
  if (normal.filename().empty()) normal = normal.parent_path();
  const std::string folder = normal.filename().string();
  std::string intrinsics_text;
  if (!options.calibration.empty()) {
    intrinsics_text = applyCameraFile(c, options).substr(2);  // without the leading ", "
  } else {
    const auto defaults = tumDefaultIntrinsics(folder);
    if (!defaults)
      throwAt(options.root,
              "cannot tell fr1/fr2/fr3 from the folder name for default intrinsics; give your camera as "
              "dataset.calibration: a camera file (docs/datasets.md, \"Your own camera\")");
    c.camera = defaults->camera;
    intrinsics_text = defaults->name + " default intrinsics";
    const bool distorted =
        std::any_of(defaults->distortion.begin(), defaults->distortion.end(), [](double d) { return d != 0; });
    if (distorted && options.undistort) {
      fillImageSize(c.camera, c.frames.front().image_path);
      const cv::Matx33d K(c.camera.fx, 0, c.camera.cx, 0, c.camera.fy, c.camera.cy, 0, 0, 1);
      cv::initUndistortRectifyMap(
          K, cv::Mat(defaults->distortion.size(), 1, CV_64F, const_cast<double*>(defaults->distortion.data())),
          cv::noArray(), K, cv::Size(c.camera.width, c.camera.height), CV_16SC2, c.undistort_map1, c.undistort_map2);
      intrinsics_text += ", undistorted";
    } else if (distorted) {
      intrinsics_text += ", images left distorted";
    }
  }
  const cv::Size first_size = readImageSize(c.frames.front().image_path);
  if (c.camera.width <= 0 || c.camera.height <= 0) {
    c.camera.width = first_size.width;
    c.camera.height = first_size.height;
  }

  std::string gt_text;
  const std::string gt_path = joinPath(options.root, "groundtruth.txt");
  if (isFile(gt_path)) {
    trajectory::Trajectory gt = trajectory::readTum(gt_path);
    // Sort by time (the files are, but association relies on it).
    std::vector<std::size_t> order(gt.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return gt.stamps[a] < gt.stamps[b]; });
    trajectory::Trajectory sorted;
    for (std::size_t k : order) sorted.push_back(gt.stamps[k], gt.poses[k]);
    trajectory::Trajectory selected;
    for (const FrameEntry& f : c.frames)
      if (const auto T_world_cam = poseAt(sorted, f.timestamp, options.gt_max_dt))
        selected.push_back(f.timestamp, *T_world_cam);
    gt_text =
        ", ground truth for " + std::to_string(selected.size()) + "/" + std::to_string(c.frames.size()) + " frames";
    c.ground_truth = std::move(selected);
  }
  c.load_color = options.load_color;
  c.load_lidar = false;
  c.description = "TUM RGB-D " + folder + " (" + std::to_string(c.frames.size()) + " frames, " + intrinsics_text +
                  rangeText(options, c.frames, all.size()) + gt_text + ")";
  return std::make_unique<LoadedDataset>(std::move(c));
}

}  // namespace detail
}  // namespace beslam::datasets
