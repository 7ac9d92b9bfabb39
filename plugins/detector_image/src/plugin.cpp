// detector_image: the SDK wrapper around Detector2D (OpenCV DNN) and GroundLifter (monocular 3D boxes).
#include <cmath>
#include <string>

#include "beslam/detector_image/image_detector.hpp"
#include "beslam/sdk/sdk.hpp"

namespace {

namespace field = beslam::sdk::field;
using namespace beslam::detector_image;

const beslam_config_field kFields[] = {
    field::Path("model", "\"\"",
                "2D detector: Darknet .cfg (with weights) or YOLO-style .onnx, e.g. "
                "../../shared/models/yolo-fastest-1.1/yolo-fastest-1.1.cfg"),
    field::Path("weights", "\"\"", "Darknet .weights for a .cfg model (unused for .onnx)"),
    field::Int("input_width", "320", 32, 4096, "network input width (multiple of 32)"),
    field::Int("input_height", "320", 32, 4096, "network input height (multiple of 32)"),
    field::Double("score_threshold", "0.3", 0.001, 0.999, "lowest class score kept"),
    field::Double("nms_threshold", "0.45", 0.01, 1, "per-class non-maximum suppression IoU"),
    field::Double("containment_threshold", "0.6", 0, 1,
                  "a box this much inside a larger box of its class is dropped as a part of it (0: off)"),
    field::DoubleList("car_classes", "[2]", 0, 10000, "model class ids reported as cars (COCO: 2)"),
    field::DoubleList("pedestrian_classes", "[0]", 0, 10000, "model class ids of persons (COCO: 0)"),
    field::DoubleList("cycle_classes", "[1, 3]", 0, 10000,
                      "bicycle/motorbike class ids: a person on one is a cyclist (COCO: 1, 3)"),
    field::Double("camera_pitch", "0", -0.5, 0.5, "camera pitch (rad, positive looking down)"),
    field::Double("max_distance", "40", 1, 1000, "boxes farther than this (m) are flagged uncertain"),
    field::Double("max_relative_uncertainty", "0.15", 0.001, 10,
                  "boxes whose distance sigma / distance exceeds this are flagged uncertain"),
    field::Double("pixel_sigma", "2", 0, 100, "bottom-edge noise (px) in the distance uncertainty"),
    field::Double("pitch_sigma", "0.005", 0, 0.5, "unmodelled road pitch (rad) in the distance uncertainty"),
    field::DoubleList("car_size", "[3.9, 1.6, 1.5]", 0.05, 30, "car prior length, width, height (m)"),
    field::DoubleList("pedestrian_size", "[0.8, 0.6, 1.75]", 0.05, 30, "pedestrian prior (m)"),
    field::DoubleList("cyclist_size", "[1.75, 0.6, 1.7]", 0.05, 30, "cyclist prior (m)"),
    field::Int("yaw_candidates", "12", 1, 360, "headings tried over 180 degrees for cars and cyclists"),
    field::Bool("drop_uncertain", "false", "drop uncertain boxes instead of flagging them"),
};

std::array<double, 3> size3(const beslam::sdk::Config& c, const char* key) {
  const std::vector<double> v = c.getList(key);
  if (v.size() != 3) throw beslam::sdk::ConfigError(std::string(key) + ": expected [length, width, height]");
  return {v[0], v[1], v[2]};
}

std::vector<int> ids(const beslam::sdk::Config& c, const char* key) {
  std::vector<int> out;
  for (double v : c.getList(key)) {
    if (v != std::floor(v)) throw beslam::sdk::ConfigError(std::string(key) + ": class ids are whole numbers");
    out.push_back(static_cast<int>(v));
  }
  return out;
}

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
  DetectorImage(const beslam::sdk::Context& context, const beslam::sdk::Config& c)
      : context_(context),
        lifter_(asConfigError([&] {
          LiftOptions o;
          // The rig's height is the dataset's (or the pipeline's dataset.camera_height), not a detector setting.
          if (!context.cameraHeight())
            throw beslam::sdk::ConfigError(
                "detector_image needs the camera's height over the road: the dataset does not know it, "
                "set dataset.camera_height in the pipeline");
          o.camera_height = *context.cameraHeight();
          o.camera_pitch = c.getDouble("camera_pitch");
          o.max_distance = c.getDouble("max_distance");
          o.max_relative_uncertainty = c.getDouble("max_relative_uncertainty");
          o.pixel_sigma = c.getDouble("pixel_sigma");
          o.pitch_sigma = c.getDouble("pitch_sigma");
          o.car_size = size3(c, "car_size");
          o.pedestrian_size = size3(c, "pedestrian_size");
          o.cyclist_size = size3(c, "cyclist_size");
          o.yaw_candidates = static_cast<int>(c.getInt("yaw_candidates"));
          return GroundLifter(context.camera(), o);
        })),
        detector_(asConfigError([&] {
          DnnOptions o;
          o.model = c.getString("model");
          o.weights = c.getString("weights");
          o.input_width = static_cast<int>(c.getInt("input_width"));
          o.input_height = static_cast<int>(c.getInt("input_height"));
          o.score_threshold = c.getDouble("score_threshold");
          o.nms_threshold = c.getDouble("nms_threshold");
          o.containment_threshold = c.getDouble("containment_threshold");
          o.car_classes = ids(c, "car_classes");
          o.pedestrian_classes = ids(c, "pedestrian_classes");
          o.cycle_classes = ids(c, "cycle_classes");
          return Detector2D(o);
        })),
        drop_uncertain_(c.getBool("drop_uncertain")) {}

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
  const beslam::sdk::Context& context_;
  GroundLifter lifter_;
  Detector2D detector_;
  bool drop_uncertain_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<DetectorImage>(
    {"detector_image", "Monocular detector lifted to 3D",
     "OpenCV DNN 2D detector (Darknet/ONNX) with boxes lifted to 3D on a flat road", {1, 0, 0}, kFields}))
