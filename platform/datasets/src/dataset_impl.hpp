// Internal: the one concrete Dataset the layout readers fill in, and helpers they share (not installed).
#pragma once

#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "beslam/datasets/camera_file.hpp"
#include "beslam/datasets/dataset.hpp"

namespace beslam::datasets::detail {

struct FrameEntry {
  std::int64_t index = 0;
  double timestamp = 0;
  std::string image_path, lidar_path, label_path;
};

// Everything a layout reader determines at open time; load() only reads files.
struct DatasetContents {
  std::string description;
  Camera camera;
  std::optional<Eigen::Isometry3d> T_cam_lidar;
  std::optional<trajectory::Trajectory> ground_truth;
  std::string label_path;
  std::optional<double> camera_height;  // metres over the road
  std::vector<FrameEntry> frames;
  bool load_color = false, load_lidar = false;
  cv::Mat undistort_map1, undistort_map2;  // applied to gray and color when not empty (a camera file, TUM fr1/fr2)
};

// image remapped with the maps (the image itself when they are empty).
cv::Mat remapped(const cv::Mat& image, const cv::Mat& map1, const cv::Mat& map2);

class LoadedDataset final : public Dataset {
 public:
  explicit LoadedDataset(DatasetContents contents) : c_(std::move(contents)) {}
  std::string describe() const override { return c_.description; }
  std::size_t size() const override { return c_.frames.size(); }
  Frame load(std::size_t i) const override;
  const Camera& camera() const override { return c_.camera; }
  std::optional<Eigen::Isometry3d> T_cam_lidar() const override { return c_.T_cam_lidar; }
  std::optional<trajectory::Trajectory> groundTruth() const override { return c_.ground_truth; }
  std::string labelPath() const override { return c_.label_path; }
  std::optional<double> cameraHeight() const override { return c_.camera_height; }
  std::int64_t frameNumber(std::size_t i) const override { return c_.frames.at(i).index; }

 private:
  DatasetContents c_;
};

std::string joinPath(const std::string& a, const std::string& b);

// A times.txt: one time in seconds a line (blank lines skipped), strictly increasing; throws "path:line: ..."
// on anything else.
std::vector<double> readTimes(const std::string& path);

// A KITTI raw timestamps.txt ("2011-09-26 13:02:25.964389445" a line, blank lines skipped): seconds since
// 1970 (long double keeps the nanoseconds); throws "path:line: ..." on anything else.
std::vector<long double> readRawTimestamps(const std::string& path);

// EuRoC's state_groundtruth_estimate0/data.csv: T_world_body by time (seconds), strictly increasing; throws
// "path:line: ..." on anything else.
trajectory::Trajectory readEurocGroundTruth(const std::string& path);

// KITTI's cameras sit 1.65 m over the road (Geiger et al. 2013, the recording platform).
constexpr double kKittiCameraHeight = 1.65;
// kKittiCameraHeight, unless the sequence is one `beslam synth` rendered: it says its own in
// sequence_dir/manifest.yaml (config.camera.mount_height). A manifest without a readable, positive height
// is an error naming the file.
double kittiCameraHeight(const std::string& sequence_dir);
bool isDirectory(const std::string& path);
bool isFile(const std::string& path);
void requireDirectory(const std::string& path, const std::string& what);
void requireFile(const std::string& path, const std::string& what);

// Files "<digits><ext>" in dir, sorted by number (other names ignored). With contiguous, the numbers must be
// 0, 1, 2, ... (error naming the first missing file); an empty listing is an error either way.
std::vector<std::pair<std::int64_t, std::string>> listNumberedFiles(const std::string& dir, const std::string& ext,
                                                                    bool contiguous);

// Positions (into `indices`, sorted ascending) of the frames options.first/last/step select; throws
// beslam::Error on a bad range or one that selects nothing from `where`.
std::vector<std::size_t> selectFrames(const std::vector<std::int64_t>& indices, const DatasetOptions& options,
                                      const std::string& where);

// The frames options.first/last/step select from numbered image files (as listNumberedFiles gives them;
// `where` names them in errors), in order, each with its number and image path; fill(frame, position in
// `images`) adds the rest (timestamp, lidar scan, labels).
std::vector<FrameEntry> selectImageFrames(const std::vector<std::pair<std::int64_t, std::string>>& images,
                                          const DatasetOptions& options, const std::string& where,
                                          const std::function<void(FrameEntry&, std::size_t)>& fill);

// "image_0" / "image_00" / "auto" -> camera number 0..3; `present(i)` says whether camera i's folder exists.
// Throws beslam::Error naming `where` when the camera is unknown or absent.
int chooseCamera(const std::string& name, const std::function<bool(int)>& present,
                 const std::function<std::string(int)>& folder_of, const std::string& where);

// Reads a KITTI pose file with one row per sequence frame and keeps the selected ones, stamped with their
// frame timestamps and pre/post-multiplied: T_world_cam = T_left * T_file * T_right.
trajectory::Trajectory selectPoses(const std::string& path, std::size_t sequence_frames,
                                   const std::vector<FrameEntry>& frames,
                                   const Eigen::Isometry3d& T_left = Eigen::Isometry3d::Identity(),
                                   const Eigen::Isometry3d& T_right = Eigen::Isometry3d::Identity());

// ", frames 10-20 step 2" when the selection is not the whole sequence; "" otherwise.
std::string rangeText(const DatasetOptions& options, const std::vector<FrameEntry>& frames, std::size_t total);

// Width/height of the first frame's image into camera (kept if already non-zero).
void fillImageSize(Camera& camera, const std::string& first_image);

// The camera of `calibration` into c: c.camera, the undistortion maps when it is distorted, and the camera
// height when it has height_over_road. `image_size` (of `image`, named in the error) must be the file's size.
// Returns the text for the dataset's description: ", camera file cam.yaml (pinhole, radial-tangential)".
// The camera file a dataset type without a camera of its own needs (`type`: "images", "video"): read, or an
// error naming the root when dataset.calibration is not set.
CameraCalibration requiredCameraFile(const DatasetOptions& options, const std::string& type);

std::string useCalibration(DatasetContents& c, const CameraCalibration& calibration, const cv::Size& image_size,
                           const std::string& image);
// With options.calibration set: the camera file replaces the layout's camera (useCalibration, checked against
// the first frame's image when the frames have images); "" and nothing changed otherwise.
std::string applyCameraFile(DatasetContents& c, const DatasetOptions& options);

// Each layout reader (one file each).
std::unique_ptr<Dataset> openKittiOdometry(const DatasetOptions& options);
std::unique_ptr<Dataset> openKittiTracking(const DatasetOptions& options);
std::unique_ptr<Dataset> openKittiRaw(const DatasetOptions& options);
std::unique_ptr<Dataset> openKittiObject(const DatasetOptions& options);
std::unique_ptr<Dataset> openTum(const DatasetOptions& options);
std::unique_ptr<Dataset> openImageFolder(const DatasetOptions& options);
std::unique_ptr<Dataset> openVideo(const DatasetOptions& options);
std::unique_ptr<Dataset> openEuroc(const DatasetOptions& options);

}  // namespace beslam::datasets::detail
