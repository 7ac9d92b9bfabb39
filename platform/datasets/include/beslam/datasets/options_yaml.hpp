// DatasetOptions from / to YAML (the `dataset:` section of a run configuration).
// Keys: type, root, sequence, camera, load_color, load_lidar, first, last, step, ego_poses, undistort,
// gt_max_dt, camera_override: {fx, fy, cx, cy, width, height}. Absent keys keep the defaults; an unknown key or
// a value of the wrong type throws beslam::Error naming `where` and the key. Paths are taken as written.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

#include "beslam/datasets/dataset.hpp"

namespace beslam::datasets {

DatasetOptions datasetOptionsFromYaml(const YAML::Node& node, const std::string& where);
YAML::Node datasetOptionsToYaml(const DatasetOptions& options);

}  // namespace beslam::datasets
