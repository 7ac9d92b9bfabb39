// mask_box: the paper's mask without LiDAR (Algorithm 1, lines 16-21). Each 3D box is clipped at the near
// plane, its eight corners (and the clip points) projected, the convex hull filled with a margin; with
// `contour`, the hull is refined to the object's edge contour (plugins/mask_common/contour.hpp). Dynamic
// boxes (and unknown ones by `unknown_policy`) are written as BESLAM_LABEL_DYNAMIC, static ones as
// BESLAM_LABEL_STATIC_BASE + track id; nearer objects overwrite farther ones.
#include "beslam/mask_common/plugin_config.hpp"
#include "beslam/sdk/sdk.hpp"
#include "mask_box_settings.hpp"  // kSettings, from ../mask_common/settings.json

namespace {

const beslam::sdk::PluginInfo kInfo(
    "mask_box", "Box projection mask",
    "Projects each near-plane-clipped 3D box, fills its convex hull (+margin), optional edge contour refinement",
    {1, 0, 0}, kSettings);

class MaskBox : public beslam::sdk::MaskGenerator {
 public:
  MaskBox(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : builder_(beslam::mask::fromCamera(context.camera()), std::nullopt, options(config)) {}

  void generate(const beslam::sdk::Frame& frame, const std::vector<beslam_box3d>& boxes, cv::Mat& mask) override {
    builder_.generate(frame.gray, beslam_point_cloud_view{}, boxes, mask);
  }

 private:
  static beslam::mask::MaskOptions options(const beslam::sdk::Config& config) {
    beslam::mask::MaskOptions o = kSettings.read(config);
    beslam::mask::checkCommonOptions(o);
    o.use_lidar = false;
    return o;
  }
  beslam::mask::MaskBuilder builder_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MaskBox>(kInfo))
