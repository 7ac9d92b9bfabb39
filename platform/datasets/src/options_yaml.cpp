#include "beslam/datasets/options_yaml.hpp"

#include <set>

#include "beslam/common/error.hpp"

namespace beslam::datasets {
namespace {

template <typename T>
void read(const YAML::Node& map, const char* key, T& value, const std::string& where, const char* expected) {
  const YAML::Node node = map[key];
  if (!node) return;
  try {
    if (!node.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "not a scalar");
    value = node.as<T>();
  } catch (const YAML::Exception&) {
    throw Error(where + ": dataset." + key + " must be " + expected);
  }
}

void checkKeys(const YAML::Node& map, const std::set<std::string>& known, const std::string& where,
               const std::string& prefix) {
  for (const auto& item : map) {
    const std::string key = item.first.as<std::string>();
    if (!known.count(key)) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw Error(where + ": unknown key " + prefix + key + " (known: " + list + ")");
    }
  }
}

}  // namespace

DatasetOptions datasetOptionsFromYaml(const YAML::Node& node, const std::string& where) {
  if (!node || !node.IsMap()) throw Error(where + ": dataset must be a map with at least type and root");
  checkKeys(node,
            {"type", "root", "sequence", "camera", "load_color", "load_lidar", "first", "last", "step", "ego_poses",
             "undistort", "gt_max_dt", "camera_override"},
            where, "dataset.");
  DatasetOptions o;
  read(node, "type", o.type, where, "a string");
  read(node, "root", o.root, where, "a string");
  read(node, "sequence", o.sequence, where, "a string");
  read(node, "camera", o.camera, where, "a string");
  read(node, "load_color", o.load_color, where, "true or false");
  read(node, "load_lidar", o.load_lidar, where, "true or false");
  read(node, "first", o.first, where, "an integer");
  read(node, "last", o.last, where, "an integer");
  read(node, "step", o.step, where, "an integer");
  read(node, "ego_poses", o.ego_poses, where, "a string");
  read(node, "undistort", o.undistort, where, "true or false");
  read(node, "gt_max_dt", o.gt_max_dt, where, "a number (seconds)");
  if (const YAML::Node cam = node["camera_override"]) {
    if (!cam.IsMap()) throw Error(where + ": dataset.camera_override must be a map {fx, fy, cx, cy[, width, height]}");
    checkKeys(cam, {"fx", "fy", "cx", "cy", "width", "height"}, where, "dataset.camera_override.");
    for (const char* key : {"fx", "fy", "cx", "cy"})
      if (!cam[key]) throw Error(where + ": dataset.camera_override needs " + key);
    Camera c;
    read(cam, "fx", c.fx, where, "a number");
    read(cam, "fy", c.fy, where, "a number");
    read(cam, "cx", c.cx, where, "a number");
    read(cam, "cy", c.cy, where, "a number");
    read(cam, "width", c.width, where, "an integer");
    read(cam, "height", c.height, where, "an integer");
    if (!(c.fx > 0) || !(c.fy > 0)) throw Error(where + ": dataset.camera_override fx and fy must be > 0");
    o.camera_override = c;
  }
  if (o.type.empty()) throw Error(where + ": dataset.type is missing");
  if (o.root.empty()) throw Error(where + ": dataset.root is missing");
  return o;
}

YAML::Node datasetOptionsToYaml(const DatasetOptions& o) {
  YAML::Node node;
  node["type"] = o.type;
  node["root"] = o.root;
  node["sequence"] = o.sequence;
  node["camera"] = o.camera;
  node["load_color"] = o.load_color;
  node["load_lidar"] = o.load_lidar;
  node["first"] = o.first;
  node["last"] = o.last;
  node["step"] = o.step;
  if (!o.ego_poses.empty()) node["ego_poses"] = o.ego_poses;
  node["undistort"] = o.undistort;
  node["gt_max_dt"] = o.gt_max_dt;
  if (o.camera_override) {
    YAML::Node cam;
    cam["fx"] = o.camera_override->fx;
    cam["fy"] = o.camera_override->fy;
    cam["cx"] = o.camera_override->cx;
    cam["cy"] = o.camera_override->cy;
    cam["width"] = o.camera_override->width;
    cam["height"] = o.camera_override->height;
    node["camera_override"] = cam;
  }
  return node;
}

}  // namespace beslam::datasets
