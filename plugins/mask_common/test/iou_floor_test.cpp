// IoU floors on a short synthetic sequence (synthetic_scene.hpp: box-built cars, textured background,
// simulated 64-beam LiDAR): median IoU of unoccluded cars within 30 m for every variant, with the
// contour-refined mask required to beat plain box projection. The floors sit below the measured
// figures (printed) so the test guards against regressions, not noise.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <opencv2/imgcodecs.hpp>

#include "beslam/mask_common/mask_builder.hpp"
#include "beslam/mask_common/score.hpp"
#include "synthetic_scene.hpp"

using namespace beslam;
using namespace beslam::mask;

namespace {

struct Variant {
  const char* name;
  MaskOptions options;
};

std::vector<Variant> variants() {
  std::vector<Variant> v;
  MaskOptions o;
  o.contour = false;
  v.push_back({"box", o});
  o.contour = true;
  v.push_back({"box_contour", o});
  o = MaskOptions{};
  o.use_lidar = true, o.point_masks = false, o.contour = false;
  v.push_back({"lidar_box", o});
  o.point_masks = true;
  v.push_back({"lidar_points", o});
  o.contour = true;
  v.push_back({"lidar_contour", o});
  return v;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

// Unoccluded: the car's visible pixels are (nearly) all of its silhouette rendered alone.
bool unoccluded(const fixture::Scene& s, const fixture::Car& car) {
  fixture::Scene alone;
  alone.K = s.K;
  alone.cars = {car};
  fixture::render(alone, 1);
  const int full = cv::countNonZero(alone.instance == car.box.track_id);
  const int visible = cv::countNonZero(s.instance == car.box.track_id);
  return full > 50 && visible >= 0.98 * full;
}

std::map<std::string, std::vector<double>> measure(int frames, bool perturb) {
  std::map<std::string, std::vector<double>> iou;
  const std::vector<Variant> vs = variants();
  for (int f = 0; f < frames; ++f) {
    const fixture::Scene s = fixture::street(100 + f, f);
    std::vector<beslam_box3d> boxes;
    for (const auto& c : s.cars) {
      beslam_box3d b = c.box;
      if (perturb) {  // a detector's error: 0.3 m along x, 4 degrees
        b.center_cam[0] += (f % 2 ? 0.3 : -0.3);
        b.yaw += (f % 3 ? 4.0 : -4.0) * M_PI / 180;
      }
      boxes.push_back(b);
    }
    beslam_point_cloud_view view{};
    view.data = s.lidar.data(), view.count = s.lidar.size() / 4, view.stride_bytes = 16;
    for (const Variant& v : vs) {
      const MaskBuilder builder(s.K, s.T_cam_lidar, v.options);
      cv::Mat mask = cv::Mat::zeros(s.gray.size(), CV_16UC1);
      builder.generate(s.gray, view, boxes, mask);
      if (const char* dump = std::getenv("BESLAM_MASK_DUMP")) {  // debugging aid: overlays per variant
        cv::Mat vis;
        cv::cvtColor(s.gray, vis, cv::COLOR_GRAY2BGR);
        vis.setTo(cv::Scalar(0, 0, 255), (mask > 0) & (s.instance == 0));
        vis.setTo(cv::Scalar(255, 0, 0), (mask == 0) & (s.instance > 0));
        for (const ObjectMask& o : builder.objects(s.gray, view, boxes))
          std::printf("frame %d %s id %d refined %d points %d from_points %d contour %d\n", f, v.name, o.box.track_id,
                      o.refined, o.lidar_points, o.from_points, o.from_contour);
        cv::imwrite(std::string(dump) + "/f" + std::to_string(f) + (perturb ? "p_" : "_") + v.name + ".png", vis);
      }
      for (const auto& c : s.cars) {
        if (Eigen::Vector3d(c.box.center_cam).norm() > 30 || !unoccluded(s, c)) continue;
        int label = 0;
        iou[v.name].push_back(objectIou(mask, s.instance, c.box.track_id, &label));
        EXPECT_EQ(label, c.box.motion_state == BESLAM_MOTION_STATIC ? 1000 + c.box.track_id : 1) << v.name;
      }
    }
  }
  return iou;
}

}  // namespace

TEST(IouFloors, ExactBoxes) {
  const auto iou = measure(6, false);
  for (const auto& [name, v] : iou)
    std::printf("exact boxes   %-14s objects %3zu  median IoU %.3f\n", name.c_str(), v.size(), median(v));
  ASSERT_GE(iou.at("box").size(), 10u);
  EXPECT_GE(median(iou.at("box_contour")), 0.80);
  EXPECT_GE(median(iou.at("box_contour")), median(iou.at("box")) + 0.05);
  EXPECT_GE(median(iou.at("lidar_contour")), 0.80);
  EXPECT_GE(median(iou.at("lidar_contour")), median(iou.at("box")) + 0.05);
  EXPECT_GE(median(iou.at("lidar_points")), median(iou.at("box")));
}

TEST(IouFloors, PerturbedBoxesLidarHelps) {
  const auto iou = measure(6, true);
  for (const auto& [name, v] : iou)
    std::printf("perturbed     %-14s objects %3zu  median IoU %.3f\n", name.c_str(), v.size(), median(v));
  EXPECT_GT(median(iou.at("lidar_box")), median(iou.at("box")));
  EXPECT_GE(median(iou.at("lidar_contour")), 0.80);
}
