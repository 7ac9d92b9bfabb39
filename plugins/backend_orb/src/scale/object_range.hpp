// Where a camera ray enters a static object's metric 3D box: the metric range of a keypoint on that
// object (FeatureSet::object_range), which gives the monocular map its scale and, once metric, holds it
// (optimize::ObjectRangeCost in local BA). docs/metric-scale.md.
#pragma once

#include <Eigen/Geometry>
#include <optional>

#include "beslam_orb/types.hpp"

namespace beslam::orb {

// ray_cam: a unit direction from the camera centre. The distance along it to the box's first face, or none
// when the ray misses the box or starts inside it.
std::optional<double> rayBoxEntry(const Eigen::Vector3d& ray_cam, const ObjectBox& box);

}  // namespace beslam::orb
