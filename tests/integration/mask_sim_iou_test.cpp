// IoU floors on `beslam synth` output (built when the sim module is in the build): 20 frames of the
// dynamic_street preset rendered in-process, oracle boxes from the frame labels, motion from the
// simulator, every variant scored on unoccluded cars within 30 m. Floors sit below the measured medians.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "beslam/mask_common/mask_builder.hpp"
#include "beslam/mask_common/score.hpp"
#include "beslam/sdk/detector.hpp"
#include "beslam/sim/synth.hpp"

using namespace beslam;
using namespace beslam::mask;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

}  // namespace

TEST(SimIou, DynamicStreetFloors) {
  sim::SynthConfig config = sim::presetConfig("dynamic_street");
  config.output.threads = 1;
  const sim::Synthesizer synth(config);
  const Eigen::Matrix<double, 3, 4> P = synth.projection();
  Intrinsics K;
  K.fx = P(0, 0), K.fy = P(1, 1), K.cx = P(0, 2), K.cy = P(1, 2);
  K.width = config.camera.width, K.height = config.camera.height;
  const Eigen::Isometry3d T_cam_lidar = synth.T_cam_velo();

  std::map<std::string, MaskOptions> variants;
  MaskOptions o;
  o.contour = false;
  variants["box"] = o;
  o.contour = true;
  variants["box_contour"] = o;
  o = MaskOptions{};
  o.use_lidar = true, o.contour = false;
  variants["lidar_points"] = o;
  o.contour = true;
  variants["lidar_contour"] = o;

  std::map<std::string, std::vector<double>> iou;
  for (int f = 0; f < synth.frameCount(); f += 15) {
    const sim::FrameRender r = synth.render(f);
    std::vector<beslam_box3d> boxes;
    for (const sim::ObjectLabel& l : r.labels) {
      beslam_box3d b = sdk::newBox();
      b.class_id = l.type == "Pedestrian" ? BESLAM_CLASS_PEDESTRIAN : BESLAM_CLASS_CAR;
      b.track_id = l.track_id;
      b.motion_state = synth.objectState(l.track_id, f).moving ? BESLAM_MOTION_DYNAMIC : BESLAM_MOTION_STATIC;
      b.center_cam[0] = l.location.x(), b.center_cam[1] = l.location.y() - l.h / 2, b.center_cam[2] = l.location.z();
      b.size[0] = l.l, b.size[1] = l.w, b.size[2] = l.h;
      b.yaw = l.ry;
      boxes.push_back(b);
    }
    beslam_point_cloud_view view{};
    view.data = r.lidar.data(), view.count = r.lidar.size() / 4, view.stride_bytes = 16;
    for (const auto& [name, options] : variants) {
      const MaskBuilder builder(K, T_cam_lidar, options);
      cv::Mat mask = cv::Mat::zeros(r.grey.size(), CV_16UC1);
      builder.generate(r.grey, view, boxes, mask);
      for (const sim::ObjectLabel& l : r.labels) {
        if ((l.type != "Car" && l.type != "Van") || l.occluded != 0 || l.truncated > 0.1 || l.location.norm() > 30)
          continue;
        if (cv::countNonZero(r.instance == l.track_id) < 50) continue;
        iou[name].push_back(objectIou(mask, r.instance, l.track_id));
      }
    }
  }
  for (const auto& [name, v] : iou)
    std::printf("beslam synth dynamic_street  %-14s objects %3zu  median IoU %.3f\n", name.c_str(), v.size(),
                median(v));
  ASSERT_GE(iou["box"].size(), 15u);
  EXPECT_GE(median(iou["lidar_contour"]), 0.80);
  EXPECT_GE(median(iou["lidar_contour"]), median(iou["box"]) + 0.05);
  EXPECT_GE(median(iou["box_contour"]), median(iou["box"]) + 0.05);
  EXPECT_GE(median(iou["lidar_points"]), median(iou["box"]) + 0.05);
}
