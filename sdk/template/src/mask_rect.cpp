// mask_rect: the simplest useful mask generator, and the SDK's worked example.
// Projects each 3D box's corners that lie in front of the camera and fills their 2D bounding rectangle,
// grown by `margin_px`: dynamic (and, if `unknown_is_dynamic`, unknown) boxes as BESLAM_LABEL_DYNAMIC,
// static boxes as BESLAM_LABEL_STATIC_BASE + track id. Coarser than mask_box's convex hull, but it
// never misses a pixel of the object, which is what a cautious ablation wants.
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "beslam/sdk/sdk.hpp"
#include "mask_rect_settings.hpp"  // Options and kSettings, generated from mask_rect.settings.json

namespace {

// What `beslam plugins` shows: id, name, one line, version, settings.
const beslam::sdk::PluginInfo kInfo("mask_rect", "Box rectangle mask",
                                    "Fills each projected 3D box's 2D bounding rectangle (SDK example)", {1, 0, 0},
                                    kSettings);

class MaskRect : public beslam::sdk::MaskGenerator {
 public:
  MaskRect(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : camera_(context.camera()), options_(kSettings.read(config)) {}

  void generate(const beslam::sdk::Frame& /*frame*/, const std::vector<beslam_box3d>& boxes, cv::Mat& mask) override {
    for (const beslam_box3d& box : boxes) {
      if (!std::isfinite(box.center_cam[2])) throw std::runtime_error("box with a non-finite centre");
      uint16_t label;
      if (box.motion_state == BESLAM_MOTION_STATIC && box.track_id >= 0)
        label = static_cast<uint16_t>(BESLAM_LABEL_STATIC_BASE + box.track_id);
      else if (box.motion_state == BESLAM_MOTION_DYNAMIC || options_.unknown_is_dynamic)
        label = BESLAM_LABEL_DYNAMIC;
      else
        continue;
      const Eigen::Matrix<double, 3, 8> p_cam = beslam::sdk::boxCorners(box);
      double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
      int visible = 0;
      for (int i = 0; i < 8; ++i) {
        if (p_cam(2, i) < options_.min_depth) continue;
        const double u = camera_.fx * p_cam(0, i) / p_cam(2, i) + camera_.cx;
        const double v = camera_.fy * p_cam(1, i) / p_cam(2, i) + camera_.cy;
        u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
        ++visible;
      }
      if (visible == 0) continue;
      const cv::Rect rect(cv::Point(static_cast<int>(std::floor(u0)) - options_.margin_px,
                                    static_cast<int>(std::floor(v0)) - options_.margin_px),
                          cv::Point(static_cast<int>(std::ceil(u1)) + options_.margin_px + 1,
                                    static_cast<int>(std::ceil(v1)) + options_.margin_px + 1));
      const cv::Rect clipped = rect & cv::Rect(0, 0, mask.cols, mask.rows);
      if (clipped.area() > 0) mask(clipped).setTo(label);
    }
  }

 private:
  beslam_camera camera_;
  Options options_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<MaskRect>(kInfo))
