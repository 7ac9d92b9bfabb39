// mask_lidar: the paper's Algorithm 1 with LiDAR. The scan is brought into the rectified camera frame
// (T_cam_lidar from the host: KITTI's R0_rect * Tr_velo_to_cam, with P's intrinsics), points in front of
// the camera and inside the image are kept and viewed top down; each box is matched to its points in and
// around it (BEV cluster), fine-tuned to them (centre and yaw; size and vertical extent kept) and
// projected back. Where an object's projected points are dense enough they give its mask directly
// (splatted, closed, hole-filled, clipped to the refined box); `contour` then refines the outline to the
// image edges near it. A frame without a scan gets plain box projection (warned once).
#include "beslam/mask_common/plugin_config.hpp"
#include "beslam/sdk/sdk.hpp"
#include "mask_lidar_settings.hpp"  // kSettings, from ../mask_common/settings.json and settings.json

namespace {

using beslam::mask::MaskOptions;

const beslam::sdk::PluginInfo kInfo(
    "mask_lidar", "LiDAR-refined mask",
    "Algorithm 1 with LiDAR: boxes fine-tuned to the scan in BEV, per-object point masks, optional contour refinement",
    {1, 0, 0}, kSettings);

class MaskLidar : public beslam::sdk::MaskGenerator {
 public:
  MaskLidar(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : context_(context), builder_(make(context, config)), box_only_(makeBoxOnly(context, config)) {}

  void generate(const beslam::sdk::Frame& frame, const std::vector<beslam_box3d>& boxes, cv::Mat& mask) override {
    if (!frame.hasLidar()) {
      if (!warned_) context_.warn("frame " + std::to_string(frame.index) + " has no LiDAR scan: box projection only");
      warned_ = true;
      box_only_.generate(frame.gray, beslam_point_cloud_view{}, boxes, mask);
      return;
    }
    builder_.generate(frame.gray, frame.lidar, boxes, mask);
  }

 private:
  static beslam::mask::MaskOptions options(const beslam::sdk::Config& config) {
    MaskOptions o = kSettings.read(config);
    beslam::mask::checkCommonOptions(o);
    o.use_lidar = true;
    return o;
  }
  static beslam::mask::MaskBuilder make(const beslam::sdk::Context& context, const beslam::sdk::Config& config) {
    if (!context.T_cam_lidar())
      throw beslam::sdk::ConfigError(
          "mask_lidar needs the LiDAR-to-camera extrinsics, and this dataset has none (use mask_box)");
    return beslam::mask::MaskBuilder(beslam::mask::fromCamera(context.camera()), context.T_cam_lidar(),
                                     options(config));
  }
  static beslam::mask::MaskBuilder makeBoxOnly(const beslam::sdk::Context& context, const beslam::sdk::Config& config) {
    beslam::mask::MaskOptions o = options(config);
    o.use_lidar = false;
    return beslam::mask::MaskBuilder(beslam::mask::fromCamera(context.camera()), std::nullopt, o);
  }

  const beslam::sdk::Context& context_;
  beslam::mask::MaskBuilder builder_;
  beslam::mask::MaskBuilder box_only_;
  bool warned_ = false;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MaskLidar>(kInfo))
