// detector_image: the SDK wrapper around Detector2D (OpenCV DNN) and GroundLifter (monocular 3D boxes).
#include <cmath>
#include <string>

#include "beslam/detector_image/image_detector.hpp"
#include "beslam/sdk/sdk.hpp"

namespace {

using beslam::sdk::nested;
using beslam::sdk::path;
using beslam::sdk::setting;
using namespace beslam::detector_image;

// What the plugin reads: the 2D detector's and the lifter's options, and its own switch.
struct Options {
  DnnOptions dnn;
  LiftOptions lift;
  bool drop_uncertain = false;
};

// Each setting once: its schema entry and the member it sets.
// clang-format off: one setting a line
const beslam::sdk::Settings<Options> kSettings{
    nested(&Options::dnn, path(&DnnOptions::model, "model", "\"\"",
                               "2D detector: Darknet .cfg (with weights) or YOLO-style .onnx, e.g. "
                               "../../shared/models/yolo-fastest-1.1/yolo-fastest-1.1.cfg")),
    nested(&Options::dnn,
           path(&DnnOptions::weights, "weights", "\"\"", "Darknet .weights for a .cfg model (unused for .onnx)")),
    nested(&Options::dnn,
           setting(&DnnOptions::input_width, "input_width", "320", 32, 4096, "network input width (multiple of 32)")),
    nested(&Options::dnn, setting(&DnnOptions::input_height, "input_height", "320", 32, 4096,
                                  "network input height (multiple of 32)")),
    nested(&Options::dnn,
           setting(&DnnOptions::score_threshold, "score_threshold", "0.3", 0.001, 0.999, "lowest class score kept")),
    nested(&Options::dnn, setting(&DnnOptions::nms_threshold, "nms_threshold", "0.45", 0.01, 1,
                                  "per-class non-maximum suppression IoU")),
    nested(&Options::dnn,
           setting(&DnnOptions::containment_threshold, "containment_threshold", "0.6", 0, 1,
                   "a box this much inside a larger box of its class is dropped as a part of it (0: off)")),
    nested(&Options::dnn, setting(&DnnOptions::car_classes, "car_classes", "[2]", 0, 10000,
                                  "model class ids reported as cars (COCO: 2)")),
    nested(&Options::dnn, setting(&DnnOptions::pedestrian_classes, "pedestrian_classes", "[0]", 0, 10000,
                                  "model class ids of persons (COCO: 0)")),
    nested(&Options::dnn, setting(&DnnOptions::cycle_classes, "cycle_classes", "[1, 3]", 0, 10000,
                                  "bicycle/motorbike class ids: a person on one is a cyclist (COCO: 1, 3)")),
    nested(&Options::lift, setting(&LiftOptions::camera_pitch, "camera_pitch", "0", -0.5, 0.5,
                                   "camera pitch (rad, positive looking down)")),
    nested(&Options::lift, setting(&LiftOptions::max_distance, "max_distance", "40", 1, 1000,
                                   "boxes farther than this (m) are flagged uncertain")),
    nested(&Options::lift, setting(&LiftOptions::max_relative_uncertainty, "max_relative_uncertainty", "0.15", 0.001,
                                   10, "boxes whose distance sigma / distance exceeds this are flagged uncertain")),
    nested(&Options::lift, setting(&LiftOptions::pixel_sigma, "pixel_sigma", "2", 0, 100,
                                   "bottom-edge noise (px) in the distance uncertainty")),
    nested(&Options::lift, setting(&LiftOptions::pitch_sigma, "pitch_sigma", "0.005", 0, 0.5,
                                   "unmodelled road pitch (rad) in the distance uncertainty")),
    nested(&Options::lift, setting(&LiftOptions::car_size, "car_size", "[3.9, 1.6, 1.5]", 0.05, 30,
                                   "car prior length, width, height (m)")),
    nested(&Options::lift, setting(&LiftOptions::pedestrian_size, "pedestrian_size", "[0.8, 0.6, 1.75]", 0.05, 30,
                                   "pedestrian prior (m)")),
    nested(&Options::lift,
           setting(&LiftOptions::cyclist_size, "cyclist_size", "[1.75, 0.6, 1.7]", 0.05, 30, "cyclist prior (m)")),
    nested(&Options::lift, setting(&LiftOptions::yaw_candidates, "yaw_candidates", "12", 1, 360,
                                   "headings tried over 180 degrees for cars and cyclists")),
    setting(&Options::drop_uncertain, "drop_uncertain", "false", "drop uncertain boxes instead of flagging them"),
};
// clang-format on

const beslam::sdk::PluginInfo kInfo("detector_image", "Monocular detector lifted to 3D",
                                    "OpenCV DNN 2D detector (Darknet/ONNX) with boxes lifted to 3D on a flat road",
                                    {1, 0, 0}, kSettings);

template <class F>
auto asConfigError(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::invalid_argument& e) {
    throw beslam::sdk::ConfigError(std::string("detector_image: ") + e.what());
  }
}

class DetectorImage : public beslam::sdk::Detector {
 public:
  DetectorImage(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : DetectorImage(context, asConfigError([&] { return kSettings.read(config); })) {}

  std::vector<beslam_box3d> detect(const beslam::sdk::Frame& frame) override {
    const cv::Mat& image = frame.color.empty() ? frame.gray : frame.color;
    if (image.empty()) throw std::invalid_argument("frame " + std::to_string(frame.index) + " has no image");
    if (image.cols != context_.camera().width || image.rows != context_.camera().height)
      throw std::invalid_argument("frame " + std::to_string(frame.index) + " is " + std::to_string(image.cols) + "x" +
                                  std::to_string(image.rows) + " but the camera is " +
                                  std::to_string(context_.camera().width) + "x" +
                                  std::to_string(context_.camera().height));
    std::vector<beslam_box3d> boxes;
    for (const Detection2D& d : detector_.detect(image)) {
      const beslam_box3d box = lifter_.lift(d);
      if (drop_uncertain_ && (box.flags & BESLAM_BOX_UNCERTAIN)) continue;
      boxes.push_back(box);
    }
    return boxes;
  }

 private:
  DetectorImage(const beslam::sdk::Context& context, Options options)
      : context_(context),
        lifter_(asConfigError([&] {
          // The rig's height is the dataset's (or the pipeline's dataset.camera_height), not a detector setting.
          if (!context.cameraHeight())
            throw beslam::sdk::ConfigError(
                "detector_image needs the camera's height over the road: the dataset does not know it, "
                "set dataset.camera_height in the pipeline");
          options.lift.camera_height = *context.cameraHeight();
          return GroundLifter(context.camera(), options.lift);
        })),
        detector_(asConfigError([&] { return Detector2D(options.dnn); })),
        drop_uncertain_(options.drop_uncertain) {}

  const beslam::sdk::Context& context_;
  GroundLifter lifter_;
  Detector2D detector_;
  bool drop_uncertain_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<DetectorImage>(kInfo))
