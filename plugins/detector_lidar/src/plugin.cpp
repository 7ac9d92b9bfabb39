// detector_lidar: the SDK wrapper around beslam::detector_lidar::LidarDetector (PCL BEV car detector).
#include <string>

#include "beslam/detector_lidar/lidar_detector.hpp"
#include "beslam/sdk/sdk.hpp"
#include "detector_lidar_settings.hpp"  // kSettings, from settings.json

namespace {

using beslam::detector_lidar::Options;

const beslam::sdk::PluginInfo kInfo(
    "detector_lidar", "LiDAR BEV car detector",
    "Cars from one LiDAR scan: ground removal, Euclidean clustering, L-shape BEV boxes (PCL)", {1, 0, 0}, kSettings);

Options readOptions(const beslam::sdk::Config& config) {
  const Options o = kSettings.read(config);
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw beslam::sdk::ConfigError(e.what());
  }
  return o;
}

beslam::detector_lidar::LidarDetector makeDetector(const beslam::sdk::Context& context,
                                                   const beslam::sdk::Config& config) {
  if (!context.T_cam_lidar())
    throw beslam::sdk::ConfigError(
        "detector_lidar needs the LiDAR-to-camera extrinsics (T_cam_lidar), and the dataset gave none: use a "
        "dataset with a LiDAR calibration (KITTI Tr_velo_to_cam) and `lidar: true`");
  std::optional<beslam_camera> camera;
  if (context.camera().width > 0 && context.camera().height > 0) camera = context.camera();
  return beslam::detector_lidar::LidarDetector(readOptions(config), *context.T_cam_lidar(), camera);
}

class DetectorLidar : public beslam::sdk::Detector {
 public:
  DetectorLidar(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : context_(context), detector_(makeDetector(context, config)) {}

  std::vector<beslam_box3d> detect(const beslam::sdk::Frame& frame) override {
    if (!frame.hasLidar()) {
      if (!warned_no_scan_)
        context_.warn("frame " + std::to_string(frame.index) +
                      " has no LiDAR scan (is `lidar: true` set in the dataset?): no boxes until one arrives");
      warned_no_scan_ = true;
      return {};
    }
    if (frame.lidar.stride_bytes != 0 && (frame.lidar.stride_bytes < 16 || frame.lidar.stride_bytes % 4 != 0))
      throw std::invalid_argument("LiDAR scan with stride " + std::to_string(frame.lidar.stride_bytes) +
                                  " bytes (need a multiple of 4, at least 16)");
    const std::size_t stride = frame.lidar.stride_bytes == 0 ? 4 : frame.lidar.stride_bytes / 4;
    beslam::detector_lidar::Stats stats;
    std::vector<beslam_box3d> boxes = detector_.detect(frame.lidar.data, frame.lidar.count, stride, &stats);
    if (stats.invalid_points > 0 && !warned_invalid_)
      context_.warn("frame " + std::to_string(frame.index) + ": " + std::to_string(stats.invalid_points) +
                    " LiDAR points with NaN/inf coordinates were skipped (reported once)");
    warned_invalid_ = warned_invalid_ || stats.invalid_points > 0;
    return boxes;
  }

 private:
  const beslam::sdk::Context& context_;
  beslam::detector_lidar::LidarDetector detector_;
  bool warned_no_scan_ = false, warned_invalid_ = false;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<DetectorLidar>(kInfo))
