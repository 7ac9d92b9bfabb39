// The object part of local bundle adjustment: one 4-DoF node per object landmark that a keyframe of the
// window sees (its box) or that map points of the window lie on, with its camera-object and
// map-point-on-surface factors (object_factors.hpp). Built per BA call: surface associations are renewed.
#pragma once

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "map/id_less.hpp"
#include "map/map_fwd.hpp"
#include "objects/object_store.hpp"

namespace beslam::orb::objects {

struct ObjectFactorOptions {
  bool enabled = false;
  bool use_boxes = true;                           // camera-object factors (the boxes are metric: only once the map is)
  double pose_weight = 1.0, surface_weight = 1.0;  // surface_weight: of all of a car's points together
  double box_sigma = 0.15, box_sigma_per_m = 0.02;  // m, m per m of range (the anchors' box noise)
  double yaw_sigma = 10.0 * M_PI / 180.0;           // rad
  double surface_sigma = 0.1, surface_gate = 0.5;   // m
  int min_surface_factors = 3;                      // a node without a box needs this many surface factors
};

struct ObjectProblem {
  struct Factor {
    std::vector<double*> blocks;  // [camera pose, node] or [point, node]
    std::unique_ptr<ceres::CostFunction> cost;
    double huber = 0;  // Huber threshold on the residual norm (chi-square 95 % of its dimension)
  };
  std::vector<ObjectEntry*> entries;  // one node each, in store order
  std::vector<Eigen::Matrix3d> R0;
  std::vector<double> storage;  // 4 per node: yaw, tx, ty, tz
  std::vector<Factor> factors;
  int box_factors = 0, surface_factors = 0;

  double* node(size_t i) { return &storage[4 * i]; }
  // Writes the optimised poses back into the landmarks.
  void writeBack();
};

// poses: every keyframe of the window (moving and fixed) with its 7-double block; moving: the ones that
// move; positions: the window's map points. Boxes of a keyframe count when its id is above the store's
// boxesAfter(object).
std::unique_ptr<ObjectProblem> buildObjectProblem(ObjectStore& store,
                                                  const std::map<KeyFrame*, double*, IdLess<KeyFrame>>& poses,
                                                  const std::set<const KeyFrame*>& moving,
                                                  const std::map<MapPoint*, double*, IdLess<MapPoint>>& positions,
                                                  const ObjectFactorOptions& options);

}  // namespace beslam::orb::objects
