// Monocular detector lifted to 3D (the core of the detector_image plugin).
//
// Detector2D runs a 2D object detector through OpenCV's DNN module, keeps cars, pedestrians and cyclists (a
// person riding a bicycle or motorbike box), and applies per-class NMS. Two output heads:
//  - "yolo": a Darknet cfg + weights such as Yolo-Fastest, or an ONNX model whose output rows are already
//    boxes (cx cy w h objectness class-scores..., in input pixels or fractions); the image is stretched to
//    the input size, RGB, scaled to [0, 1].
//  - "yolox": YOLOX's raw head (ONNX, e.g. YOLOX-Nano): one row per cell of the stride 8, 16 and 32 grids
//    (row-major, in that order), x y as offsets in cells, w h as logs, then objectness and class scores; the
//    image is letterboxed (aspect kept, top-left, the rest grey 114), BGR, 0-255.
// "auto" (the default) takes "yolox" for an ONNX model whose output has exactly one row per grid cell of
// the input size, else "yolo".
// GroundLifter lifts each 2D box to a 3D box in the camera frame under a flat-ground assumption: the camera
// sits camera_height above the road, pitched down by camera_pitch; a class size prior is placed on the road
// so that its projection's bottom edge and horizontal centre (or the edge that is not cut by the image
// border) match the 2D box, with the yaw chosen among candidates by the 2D box width, biased towards the
// road direction. Boxes too far, too uncertain in distance, or cut by the image border get
// BESLAM_BOX_UNCERTAIN.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <string>
#include <vector>

#include "beslam/data.h"

namespace beslam::detector_image {

struct Detection2D {
  int32_t class_id = BESLAM_CLASS_UNKNOWN;  // BESLAM_CLASS_CAR / PEDESTRIAN / CYCLIST
  float score = 0;
  cv::Rect2d box;  // pixels in the input image
};

struct DnnOptions {
  std::string model;          // .cfg (Darknet) or .onnx
  std::string weights;        // .weights for a Darknet model; unused for ONNX
  std::string head = "auto";  // "auto" | "yolo" | "yolox" (see above)
  int input_width = 320, input_height = 320;
  double score_threshold = 0.3;
  double nms_threshold = 0.45;
  double containment_threshold = 0.6;         // a box this much inside a larger one of its class is dropped (0: off)
  std::vector<int> car_classes = {2};         // COCO car
  std::vector<int> pedestrian_classes = {0};  // COCO person
  std::vector<int> cycle_classes = {1, 3};    // COCO bicycle, motorbike: a person on one is a cyclist
};

// Throws std::invalid_argument naming the path when the model or weights file is missing, unreadable or
// cannot be parsed by OpenCV, and for bad options.
class Detector2D {
 public:
  explicit Detector2D(const DnnOptions& options);
  // image: CV_8UC3 BGR or CV_8UC1 grey, any size.
  std::vector<Detection2D> detect(const cv::Mat& image);
  const DnnOptions& options() const { return options_; }
  // The head in use ("yolo" or "yolox"; "auto" resolved when the model was loaded).
  const std::string& head() const { return head_; }

 private:
  // The network's outputs for one image, and the factor from input pixels back to image pixels (yolox).
  void forward(const cv::Mat& bgr, double& letterbox_scale);
  size_t yoloxCells() const;  // rows of a YOLOX head at the input size

  DnnOptions options_;
  cv::dnn::Net net_;
  std::vector<std::string> out_names_;
  bool onnx_ = false;
  std::string head_;
  cv::Mat bgr_, blob_, letterbox_;
  std::vector<cv::Mat> outs_;
};

struct LiftOptions {
  double camera_height = 1.65;                       // m above the road (KITTI cam 0/2: 1.65)
  double camera_pitch = 0.0;                         // rad, positive when the camera looks down
  double max_distance = 40.0;                        // m: farther boxes are uncertain
  double max_relative_uncertainty = 0.15;            // sigma(distance)/distance above this: uncertain
  double pixel_sigma = 2.0;                          // px: bottom-edge noise
  double pitch_sigma = 0.005;                        // rad: road pitch unknown to the flat-ground model
  double border_px = 3.0;                            // a box edge this close to the image border is cut
  std::array<double, 3> car_size = {3.9, 1.6, 1.5};  // length width height (m)
  std::array<double, 3> pedestrian_size = {0.8, 0.6, 1.75};
  std::array<double, 3> cyclist_size = {1.75, 0.6, 1.7};
  int yaw_candidates = 12;          // cars and cyclists: headings tried over 180 degrees
  double yaw_prior_sigma = 0.5;     // rad: preference for road-aligned headings (yaw -pi/2)
  double height_consistency = 2.0;  // road distance above this times the height-prior distance: use the
                                    // height prior instead, flagged uncertain

  void validate() const;  // throws std::invalid_argument naming the field
};

class GroundLifter {
 public:
  GroundLifter(const beslam_camera& camera, const LiftOptions& options);
  // A 3D box (class, score, bbox2d set; HAS_BBOX2D; UNCERTAIN when warranted) for one 2D detection.
  beslam_box3d lift(const Detection2D& detection) const;

 private:
  beslam_camera camera_;
  LiftOptions options_;
};

}  // namespace beslam::detector_image
