// A video file (type video): any file cv::VideoCapture opens. Opening reads the file through once to count
// its frames and take their container timestamps; load(i) decodes forward from the last frame read (the
// runner reads in order) and reopens the file to go back. Timestamps: frame / fps of the camera file, else
// the container's per-frame times when they increase, else frame / the container's frame rate.
#include <cmath>
#include <filesystem>
#include <mutex>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>

#include "beslam/common/error.hpp"
#include "dataset_impl.hpp"

namespace beslam::datasets::detail {
namespace {

// OpenCV's own log lines (each backend that declines a file says so on stderr) off while it lives: a file
// that no backend opens is then one error line.
class QuietOpenCvLog {
 public:
  QuietOpenCvLog() : previous_(cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT)) {}
  ~QuietOpenCvLog() { cv::utils::logging::setLogLevel(previous_); }
  QuietOpenCvLog(const QuietOpenCvLog&) = delete;
  QuietOpenCvLog& operator=(const QuietOpenCvLog&) = delete;

 private:
  cv::utils::logging::LogLevel previous_;
};

class VideoDataset final : public Dataset {
 public:
  VideoDataset(DatasetContents contents, std::string path) : c_(std::move(contents)), path_(std::move(path)) {}
  std::string describe() const override { return c_.description; }
  std::size_t size() const override { return c_.frames.size(); }
  const Camera& camera() const override { return c_.camera; }
  std::optional<Eigen::Isometry3d> T_cam_lidar() const override { return std::nullopt; }
  std::optional<trajectory::Trajectory> groundTruth() const override { return c_.ground_truth; }
  std::optional<double> cameraHeight() const override { return c_.camera_height; }
  std::int64_t frameNumber(std::size_t i) const override { return c_.frames.at(i).index; }

  Frame load(std::size_t i) const override {
    if (i >= c_.frames.size())
      throw Error(c_.description + ": frame position " + std::to_string(i) + " out of range (size " +
                  std::to_string(c_.frames.size()) + ")");
    const FrameEntry& entry = c_.frames[i];
    cv::Mat image;
    try {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!capture_.isOpened() || entry.index < next_) {
        capture_.release();
        next_ = 0;
        if (!capture_.open(path_)) throwAt(path_, "cannot open the video again");
      }
      for (; next_ < entry.index; ++next_)
        if (!capture_.grab()) throwAt(path_, "cannot decode frame " + std::to_string(next_));
      ++next_;  // past this frame whether or not it decodes
      if (!capture_.read(image) || image.empty()) throwAt(path_, "cannot decode frame " + std::to_string(entry.index));
    } catch (const cv::Exception& e) {
      throwAt(path_, "OpenCV cannot decode frame " + std::to_string(entry.index) + ": " + e.what());
    }
    if (image.cols != c_.camera.width || image.rows != c_.camera.height)
      throwAt(path_, "frame " + std::to_string(entry.index) + " is " + std::to_string(image.cols) + "x" +
                         std::to_string(image.rows) + ", expected " + std::to_string(c_.camera.width) + "x" +
                         std::to_string(c_.camera.height));
    Frame frame;
    frame.index = entry.index;
    frame.timestamp = entry.timestamp;
    frame.image_path = entry.image_path;
    cv::Mat gray;
    if (image.channels() == 3) {
      cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
      if (c_.load_color) frame.color = remapped(image, c_.undistort_map1, c_.undistort_map2);
    } else if (image.channels() == 4) {
      cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
    } else {
      gray = image;
    }
    if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U, gray.depth() == CV_16U ? 1.0 / 256 : 1.0);
    frame.gray = remapped(gray, c_.undistort_map1, c_.undistort_map2);
    return frame;
  }

 private:
  DatasetContents c_;
  std::string path_;
  mutable std::mutex mutex_;
  mutable cv::VideoCapture capture_;
  mutable std::int64_t next_ = 0;  // the frame the next read returns
};

}  // namespace

std::unique_ptr<Dataset> openVideo(const DatasetOptions& options) {
  requireFile(options.root, "video file");
  const CameraCalibration calibration = requiredCameraFile(options, "video");

  cv::VideoCapture capture;
  try {
    const QuietOpenCvLog quiet;
    capture.open(options.root);
  } catch (const cv::Exception& e) {
    throwAt(options.root, std::string("OpenCV cannot open the video: ") + e.what());
  }
  if (!capture.isOpened())
    throwAt(options.root, "OpenCV's VideoCapture cannot open this file (not a video, or no backend for its format)");
  const double container_fps = capture.get(cv::CAP_PROP_FPS);
  std::vector<double> container_times;  // seconds, per frame
  cv::Size size;
  try {
    for (bool first = true; capture.grab(); first = false) {
      container_times.push_back(capture.get(cv::CAP_PROP_POS_MSEC) / 1000.0);
      if (first) {
        cv::Mat image;
        if (!capture.retrieve(image) || image.empty()) throwAt(options.root, "cannot decode frame 0");
        size = image.size();
      }
    }
  } catch (const cv::Exception& e) {
    throwAt(options.root, "OpenCV cannot decode frame " + std::to_string(container_times.size()) + ": " + e.what());
  }
  if (container_times.empty()) throwAt(options.root, "the video has no frames OpenCV can decode");
  const std::size_t total = container_times.size();

  std::vector<double> times(total);
  std::ostringstream time_text;
  bool increasing = total > 1;
  for (std::size_t k = 1; k < total; ++k)
    increasing = increasing && std::isfinite(container_times[k]) && container_times[k] > container_times[k - 1];
  if (calibration.fps) {
    for (std::size_t k = 0; k < total; ++k) times[k] = static_cast<double>(k) / *calibration.fps;
    time_text << ", " << *calibration.fps << " fps (camera file)";
  } else if (increasing) {
    for (std::size_t k = 0; k < total; ++k) times[k] = container_times[k] - container_times[0];
    time_text << ", container timestamps";
  } else if (container_fps > 0 && std::isfinite(container_fps)) {
    for (std::size_t k = 0; k < total; ++k) times[k] = static_cast<double>(k) / container_fps;
    time_text << ", " << container_fps << " fps (container)";
  } else {
    throwAt(options.root,
            "the video has neither frame times nor a frame rate; give fps in the camera file " + calibration.source);
  }

  std::vector<std::int64_t> indices(total);
  for (std::size_t k = 0; k < total; ++k) indices[k] = static_cast<std::int64_t>(k);
  DatasetContents c;
  for (std::size_t p : selectFrames(indices, options, options.root)) {
    FrameEntry f;
    f.index = static_cast<std::int64_t>(p);
    f.timestamp = times[p];
    f.image_path = options.root + "#" + std::to_string(p);
    c.frames.push_back(std::move(f));
  }
  const std::string camera_text = useCalibration(c, calibration, size, options.root);
  if (!options.ego_poses.empty()) c.ground_truth = selectPoses(options.ego_poses, total, c.frames);
  c.load_color = options.load_color;
  c.description = "video " + std::filesystem::path(options.root).filename().string() + " (" +
                  std::to_string(c.frames.size()) + " frames" + time_text.str() + camera_text +
                  rangeText(options, c.frames, total) +
                  (options.ego_poses.empty() ? "" : ", poses " + options.ego_poses) + ")";
  return std::make_unique<VideoDataset>(std::move(c), options.root);
}

}  // namespace beslam::datasets::detail
