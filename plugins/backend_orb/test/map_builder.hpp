// Test helpers. buildMap: a Map whose keyframes all observe all given world points (keypoint i = point i,
// level 0). Observations are the points' projections under the true poses plus the given pixel noise; the
// keyframes get the given (possibly perturbed) poses and the map points the given positions.
// buildRoad: a drive down a road, each keyframe seeing only the points 4-30 m ahead of it (a banded
// covisibility, as a real map has), poses and points perturbed; for global BA.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "features/feature_set.hpp"
#include "features/scale_pyramid.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"

namespace beslam::orb::test {

inline Eigen::Vector2d project(const Camera& cam, const Eigen::Isometry3d& T_cw, const Eigen::Vector3d& p_world) {
  const Eigen::Vector3d p = T_cw * p_world;
  return {cam.fx * p.x() / p.z() + cam.cx, cam.fy * p.y() / p.z() + cam.cy};
}

// A keyframe's features: the given level-0 keypoints with blank descriptors, labels and colours.
inline std::shared_ptr<FeatureSet> blankFeatures(const Camera& cam, std::vector<cv::KeyPoint> keypoints) {
  auto f = std::make_shared<FeatureSet>();
  f->width = cam.width;
  f->height = cam.height;
  f->keypoints = std::move(keypoints);
  f->descriptors = cv::Mat(static_cast<int>(f->keypoints.size()), 32, CV_8U, cv::Scalar(0));
  f->labels.assign(f->keypoints.size(), 0);
  f->colours.assign(f->keypoints.size(), cv::Vec3b(0, 0, 0));
  f->buildGrid();
  return f;
}

inline std::vector<KeyFrame*> buildMap(Map& map, const Camera& cam, const ScalePyramid& pyr,
                                       const std::vector<Eigen::Isometry3d>& true_T_cw,
                                       const std::vector<Eigen::Isometry3d>& start_T_cw,
                                       const std::vector<Eigen::Vector3d>& true_points,
                                       const std::vector<Eigen::Vector3d>& start_points, double pixel_noise,
                                       uint64_t seed) {
  std::mt19937 rng(static_cast<unsigned>(seed));
  std::normal_distribution<double> noise(0, pixel_noise);
  std::vector<KeyFrame*> kfs;
  for (size_t k = 0; k < true_T_cw.size(); ++k) {
    std::vector<cv::KeyPoint> keypoints;
    for (const auto& p : true_points) {
      Eigen::Vector2d uv = project(cam, true_T_cw[k], p);
      if (pixel_noise > 0) uv += Eigen::Vector2d(noise(rng), noise(rng));
      keypoints.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f, 0.f, 1.f, 0);
    }
    Frame frame(static_cast<int64_t>(k), 0.1 * static_cast<double>(k), blankFeatures(cam, std::move(keypoints)));
    frame.T_cw = start_T_cw[k];
    kfs.push_back(map.createKeyFrame(frame, cam, pyr));
  }
  for (size_t i = 0; i < start_points.size(); ++i) {
    MapPoint* mp = map.createMapPoint(start_points[i], kfs[0]);
    for (KeyFrame* kf : kfs) {
      kf->addPoint(mp, i);
      mp->addObservation(kf, i);
    }
    mp->updateNormalAndDepth();
  }
  for (KeyFrame* kf : kfs) kf->updateConnections();
  return kfs;
}

// The road's frame `distance` m along it (a camera looking down the road there): a bend of 1 km radius.
inline Eigen::Isometry3d roadAt(double distance) {
  constexpr double kCurvature = 1e-3;  // 1 / m
  const double heading = kCurvature * distance;
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  T_wc.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_wc.translation() = Eigen::Vector3d((1 - std::cos(heading)) / kCurvature, 0, std::sin(heading) / kCurvature);
  return T_wc;
}

// n_keyframes cameras `spacing` m apart down the road (roadAt) and points_per_metre points a metre of road
// (up to 8 m to either side, 2 m up or down), each observed (0.5 px noise) by the cameras it is 4-30 m
// ahead of and in the image of (26 / spacing cameras). Every camera but the first is moved by about 5 cm
// and 0.17 degrees, every point by about 5 cm. ranges: each keypoint also carries its point's true range from
// the camera, as a scan would give it (Lidar: FeatureSet::lidar_range) or a parked car's box (Object:
// FeatureSet::object_range, as if every point lay on a car where its ray enters the box).
enum class RoadRanges { None, Lidar, Object };
inline std::vector<KeyFrame*> buildRoad(Map& map, const Camera& cam, const ScalePyramid& pyr, int n_keyframes,
                                        int points_per_metre, uint64_t seed, double spacing = 1.0,
                                        RoadRanges with_ranges = RoadRanges::None) {
  std::mt19937 rng(static_cast<unsigned>(seed));
  const double length = spacing * (n_keyframes - 1);
  std::uniform_real_distribution<double> ux(-8, 8), uy(-2, 2), ud(5, length + 29);
  std::normal_distribution<double> perturb(0, 0.05), pixel(0, 0.5);
  std::vector<Eigen::Vector3d> points;
  const int n_points = static_cast<int>(points_per_metre * (length + 24));
  for (int i = 0; i < n_points; ++i) {
    const double x = ux(rng), y = uy(rng);
    points.push_back(roadAt(ud(rng)) * Eigen::Vector3d(x, y, 0));
  }
  std::vector<KeyFrame*> kfs;
  std::vector<std::vector<int>> seen(n_keyframes);  // point indices, in keypoint order
  for (int k = 0; k < n_keyframes; ++k) {
    const Eigen::Isometry3d T_cw = roadAt(spacing * k).inverse();
    std::vector<cv::KeyPoint> keypoints;
    std::vector<float> ranges;
    for (int i = 0; i < static_cast<int>(points.size()); ++i) {
      const double ahead = (T_cw * points[i]).z();
      if (ahead < 4 || ahead > 30) continue;
      const Eigen::Vector2d uv = project(cam, T_cw, points[i]) + Eigen::Vector2d(pixel(rng), pixel(rng));
      if (uv.x() < 0 || uv.y() < 0 || uv.x() >= cam.width || uv.y() >= cam.height) continue;
      keypoints.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f, 0.f, 1.f, 0);
      ranges.push_back(static_cast<float>((T_cw * points[i]).norm()));
      seen[k].push_back(i);
    }
    std::shared_ptr<FeatureSet> features = blankFeatures(cam, std::move(keypoints));
    if (with_ranges == RoadRanges::Lidar) features->lidar_range = std::move(ranges);
    if (with_ranges == RoadRanges::Object) features->object_range = std::move(ranges);
    Frame frame(k, 0.1 * k, features);
    frame.T_cw = T_cw;
    if (k > 0) {
      frame.T_cw.translation() += Eigen::Vector3d(perturb(rng), perturb(rng), perturb(rng));
      frame.T_cw.linear() = Eigen::AngleAxisd(0.003, Eigen::Vector3d::UnitX()).toRotationMatrix() * frame.T_cw.linear();
    }
    kfs.push_back(map.createKeyFrame(frame, cam, pyr));
  }
  std::vector<MapPoint*> mps(points.size(), nullptr);
  for (int k = 0; k < n_keyframes; ++k)
    for (size_t j = 0; j < seen[k].size(); ++j) {
      const int i = seen[k][j];
      if (!mps[i])
        mps[i] = map.createMapPoint(points[i] + Eigen::Vector3d(perturb(rng), perturb(rng), perturb(rng)), kfs[k]);
      kfs[k]->addPoint(mps[i], j);
      mps[i]->addObservation(kfs[k], j);
    }
  for (MapPoint* mp : mps)
    if (mp) mp->updateNormalAndDepth();
  for (KeyFrame* kf : kfs) kf->updateConnections();
  return kfs;
}

}  // namespace beslam::orb::test
