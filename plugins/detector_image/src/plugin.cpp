// detector_image: the SDK wrapper around Detector2D (OpenCV DNN) and GroundLifter (monocular 3D boxes).
#include <cmath>
#include <string>

#include "beslam/detector_image/image_detector.hpp"
#include "beslam/sdk/sdk.hpp"
#include "detector_image_settings.hpp"  // Options and kSettings, from settings.json

namespace {

using namespace beslam::detector_image;

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
