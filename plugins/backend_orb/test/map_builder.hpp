// Test helper: a Map whose keyframes all observe all given world points (keypoint i = point i, level 0).
// Observations are the points' projections under the true poses plus the given pixel noise; the
// keyframes get the given (possibly perturbed) poses and the map points the given positions.
#pragma once

#include <Eigen/Geometry>
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
    auto f = std::make_shared<FeatureSet>();
    f->width = cam.width;
    f->height = cam.height;
    for (const auto& p : true_points) {
      Eigen::Vector2d uv = project(cam, true_T_cw[k], p);
      if (pixel_noise > 0) uv += Eigen::Vector2d(noise(rng), noise(rng));
      f->keypoints.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f, 0.f, 1.f, 0);
    }
    f->descriptors = cv::Mat(static_cast<int>(true_points.size()), 32, CV_8U, cv::Scalar(0));
    f->labels.assign(true_points.size(), 0);
    f->colours.assign(true_points.size(), cv::Vec3b(0, 0, 0));
    f->buildGrid();
    Frame frame(static_cast<int64_t>(k), 0.1 * static_cast<double>(k), f);
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

}  // namespace beslam::orb::test
