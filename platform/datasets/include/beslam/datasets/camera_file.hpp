// The camera file (`dataset.calibration: FILE`, DatasetOptions::calibration): the one place a camera is
// defined, for every dataset type. A YAML map:
//
//   model: pinhole                 # pinhole | fisheye
//   width: 752                     # pixels, the images' size
//   height: 480
//   fx: 458.654                    # pixels
//   fy: 457.296
//   cx: 367.215
//   cy: 248.375
//   distortion: [-0.28, 0.07, 0.0002, 0.00002, 0.0]
//       # pinhole: optional, [k1, k2, p1, p2, k3] radial-tangential as OpenCV has it (4 values: k3 = 0);
//       # fisheye: required, [k1, k2, k3, k4] equidistant as cv::fisheye has it
//   fps: 20                        # optional: frame rate, for image folders without times.txt and videos
//   height_over_road: 1.65         # optional: metres from the camera down to the road
//
// Images of a distorted camera (pinhole with a non-zero coefficient, or any fisheye) are remapped once per
// frame onto the pinhole camera with the same K, with maps made once (cv::initUndistortRectifyMap,
// cv::fisheye::initUndistortRectifyMap); the dataset's camera() is that pinhole camera.
// Every bad value is one beslam::Error "FILE:LINE: KEY: what is wrong (what is accepted)".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "beslam/datasets/dataset.hpp"

namespace beslam::datasets {

enum class CameraModel { Pinhole, Fisheye };

struct CameraCalibration {
  std::string source;  // the file it came from, for messages
  CameraModel model = CameraModel::Pinhole;
  Camera camera;                   // K and the image size; the undistorted images keep this K
  std::vector<double> distortion;  // pinhole: k1 k2 p1 p2 k3 (all zero: none); fisheye: k1 k2 k3 k4
  std::optional<double> fps;
  std::optional<double> height_over_road;  // metres

  // True when the images need remapping: a pinhole camera with a non-zero coefficient, or a fisheye.
  bool distorted() const;
  // "pinhole", "pinhole, radial-tangential" or "fisheye, equidistant".
  std::string modelText() const;
};

// Reads and validates a camera file; throws beslam::Error naming the file, the key and what is accepted.
CameraCalibration readCameraFile(const std::string& path);

// The maps (CV_16SC2 + CV_16UC1, for cv::remap) taking the distorted images onto the pinhole camera with
// the same K and size.
void undistortionMaps(const CameraCalibration& calibration, cv::Mat& map1, cv::Mat& map2);

}  // namespace beslam::datasets
