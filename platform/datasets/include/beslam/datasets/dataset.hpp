// Dataset readers: the frames (image, optional LiDAR scan), camera, extrinsics and ground truth the host
// feeds the pipeline from. openDataset() validates the whole layout up front (folders, calibration, frame
// lists, timestamp counts, ground-truth counts) and throws beslam::Error naming the missing or malformed
// file; load(i) reads one frame and throws beslam::Error naming the file when an image or scan is missing,
// truncated or undecodable. Datasets are immutable after opening, so load() may be called from any thread.
// Frames: p_cam = T_cam_lidar * p_lidar maps a LiDAR point into the chosen camera's rectified frame
// (x right, y down, z forward), where K * p_cam projects it; ground truth is T_world_cam of that camera.
// Layouts, options and conventions: docs/datasets.md.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "beslam/common/frame_ranges.hpp"
#include "beslam/formats/camera.hpp"
#include "beslam/trajectory/trajectory.hpp"

namespace beslam::datasets {

// Pinhole camera of rectified (or undistorted) images (beslam/formats/camera.hpp).
using formats::Camera;

struct Frame {
  std::int64_t index = 0;  // frame number in the sequence (file number), not the position in the range
  double timestamp = 0;    // seconds
  std::string image_path;
  cv::Mat gray;                   // CV_8UC1; empty only for an image-less sequence (kitti_tracking, see there)
  cv::Mat color;                  // CV_8UC3 BGR, empty unless options.load_color and the images are colour
  std::vector<float> lidar_xyzi;  // x y z intensity in the LiDAR frame; empty unless load_lidar and available
  std::string lidar_path;         // set whenever the dataset has a scan for this frame (even if not loaded)
  std::string label_path;         // KITTI object/tracking label file for this frame, if present
};

struct DatasetOptions {
  std::string type;             // "kitti_odometry" | "kitti_tracking" | "kitti_raw" | "kitti_object" | "tum" |
                                // "images" | "video" | "euroc"
  std::string root;             // .../kitti/odometry, .../kitti/tracking/training, .../kitti/raw (holds the date
                                // folders), .../kitti/object/training, a TUM sequence folder, a folder of
                                // images, a video file, or an EuRoC/ASL folder (holding mav0/)
  std::string sequence;         // "06", "0007", "2011_09_26_drive_0001_sync"; kitti_object: "000008" for one
                                // frame or "" for every index file; unused for tum, images, video, euroc
  std::string camera = "auto";  // kitti: "image_0" (grey left) | "image_2" (colour left) | "image_1" |
                                // "image_3" | "auto" (image_0 if present, else image_2)
  bool load_color = false, load_lidar = false;
  std::int64_t first = 0, last = -1, step = 1;  // frame numbers, last inclusive, -1 = to the end

  // Additions.
  std::string calibration;  // a camera file (camera_file.hpp), any type: replaces the layout's camera (KITTI's
                            // P_i intrinsics, TUM's fr1/fr2/fr3 defaults, EuRoC's sensor.yaml); required for
                            // images and video. Distorted images are undistorted onto the same K.
  std::string ego_poses;    // kitti_tracking / kitti_raw / kitti_odometry: a KITTI-format pose file, one row per
                            // frame of the sequence, taken as T_world_cam of the chosen camera (ground truth or
                            // a reference estimate); for kitti_odometry it replaces poses/NN.txt. Not accepted
                            // for kitti_object and tum.
  std::string name;         // kitti_odometry: what describe() calls the sequence instead of "KITTI odometry NN"
                            // (a `beslam synth` rendering in KITTI's layout: "synthetic urban_loop")
  bool undistort = true;    // tum: undistort fr1/fr2 images with the published distortion of their defaults
  double gt_max_dt = 0.02;  // tum: ground truth is interpolated between samples bracketing a frame; with no
                            // bracket, the nearest sample within this many seconds is used, else none
};

class Dataset {
 public:
  virtual ~Dataset() = default;
  virtual std::string describe() const = 0;  // "KITTI odometry 06 (51 frames, image_0)"
  virtual std::size_t size() const = 0;
  // Frame i of the selected range (0 <= i < size()); throws beslam::Error naming the file on a missing,
  // truncated or unreadable image or scan, or an image whose size differs from camera().
  virtual Frame load(std::size_t i) const = 0;
  virtual const Camera& camera() const = 0;
  virtual std::optional<Eigen::Isometry3d> T_cam_lidar() const = 0;  // LiDAR -> chosen rectified camera
  // T_world_cam of the chosen camera, one pose per selected frame that has one, stamped with the frame's
  // timestamp (KITTI: world = the chosen camera at frame 0 of the sequence).
  virtual std::optional<trajectory::Trajectory> groundTruth() const = 0;
  virtual std::string labelPath() const { return {}; }  // tracking labels file if present (oracle detectors)
  // The rig: the chosen camera's height over the road in metres, where the layout knows it (KITTI's
  // cameras: 1.65 m; a `beslam synth` sequence: camera.mount_height from its manifest.yaml; TUM: none; a camera
  // file's height_over_road replaces it).
  virtual std::optional<double> cameraHeight() const { return std::nullopt; }
  // The sequence frame number of frame i of the selected range (what load(i).index will be), without
  // reading the frame.
  virtual std::int64_t frameNumber(std::size_t i) const = 0;
};

// A camera blackout: the dataset with the images of the frames in `ranges` all black (grey and colour,
// every pixel 0, same size and type); everything else (LiDAR scans, labels, timestamps, ground truth) as
// it was. Throws beslam::Error when a range holds none of the dataset's selected frames.
std::unique_ptr<Dataset> blackOut(std::unique_ptr<Dataset> dataset, const std::vector<FrameRange>& ranges);

// Opens and validates a dataset; throws beslam::Error naming the missing file or folder, the malformed
// file:line, or the bad option.
std::unique_ptr<Dataset> openDataset(const DatasetOptions& options);

// The accepted DatasetOptions::type names.
std::vector<std::string> datasetTypes();

}  // namespace beslam::datasets
