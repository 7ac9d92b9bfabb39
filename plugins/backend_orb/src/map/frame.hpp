// The frame being tracked: its features, matched map points, outlier flags, pose T_cw and, once
// computed, its bag of words.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

#include "features/feature_set.hpp"
#include "map/map_fwd.hpp"
#include "place/vocabulary.hpp"

namespace beslam::orb {

struct Frame {
  int64_t index = -1;
  double timestamp = 0;
  std::shared_ptr<const FeatureSet> features;
  std::vector<MapPoint*> points;
  std::vector<bool> outlier;
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  bool has_pose = false;
  KeyFrame* reference = nullptr;
  // Bag of words and direct index (filled by the tracker when a vocabulary is loaded and they are needed).
  bool has_bow = false;
  place::BowVector bow;
  place::FeatureVector feature_vector;

  Frame() = default;
  Frame(int64_t idx, double ts, std::shared_ptr<const FeatureSet> f)
      : index(idx),
        timestamp(ts),
        features(std::move(f)),
        points(features->size(), nullptr),
        outlier(features->size(), false) {}
  size_t size() const { return points.size(); }
  Eigen::Vector3d centre() const { return T_cw.inverse().translation(); }
  void clearMatches() {
    std::fill(points.begin(), points.end(), nullptr);
    std::fill(outlier.begin(), outlier.end(), false);
  }
};

}  // namespace beslam::orb
