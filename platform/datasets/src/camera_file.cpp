#include "beslam/datasets/camera_file.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/yaml_load.hpp"

namespace beslam::datasets {
namespace {

const char* const kKeys[] = {"model", "width", "height",     "fx",  "fy",
                             "cx",    "cy",    "distortion", "fps", "height_over_road"};

std::string knownKeys() {
  std::string text;
  for (const char* k : kKeys) text += (text.empty() ? "" : ", ") + std::string(k);
  return text;
}

// "file:line" of a node read from the file, "file" for one without a position.
[[noreturn]] void fail(const std::string& path, const YAML::Node& node, const std::string& key,
                       const std::string& message) {
  throw Error(yamlWhere(path, node) + ": " + key + ": " + message);
}

double number(const YAML::Node& node, const std::string& path, const std::string& key, const std::string& accepted) {
  double value = 0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value))
    fail(path, node, key, "'" + yamlText(node) + "' is not " + accepted);
  return value;
}

}  // namespace

bool CameraCalibration::distorted() const {
  return model == CameraModel::Fisheye ||
         std::any_of(distortion.begin(), distortion.end(), [](double d) { return d != 0; });
}

std::string CameraCalibration::modelText() const {
  if (model == CameraModel::Fisheye) return "fisheye, equidistant";
  return distorted() ? "pinhole, radial-tangential" : "pinhole";
}

CameraCalibration readCameraFile(const std::string& path) {
  std::string text;
  try {
    text = readFile(path);
  } catch (const Error&) {
    throwAt(path, "cannot read the camera file (dataset.calibration)");
  }
  // Duplicate keys, alias bombs, deep nesting and keys that are not names are errors (beslam/common/yaml_load.hpp).
  YAML::Node root = loadYaml(text, path);
  if (!root.IsMap())
    throwAt(path, "a camera file is a map with the keys model, width, height, fx, fy, cx, cy (docs/datasets.md)");
  try {
    for (const auto& kv : root) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : yamlText(kv.first);
      if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys))
        fail(path, kv.first, key, "unknown key (known: " + knownKeys() + ")");
    }
    auto required = [&](const char* key) {
      const YAML::Node node = root[key];
      if (!node.IsDefined() || node.IsNull())
        throwAt(path, std::string(key) + ": missing (a camera file needs model, width, height, fx, fy, cx, cy)");
      return node;
    };

    CameraCalibration c;
    c.source = path;
    const YAML::Node model = required("model");
    if (model.IsScalar() && model.Scalar() == "pinhole") {
      c.model = CameraModel::Pinhole;
    } else if (model.IsScalar() && model.Scalar() == "fisheye") {
      c.model = CameraModel::Fisheye;
    } else {
      fail(path, model, "model", "unknown camera model '" + yamlText(model) + "' (accepted: pinhole, fisheye)");
    }

    for (const char* key : {"width", "height"}) {
      const YAML::Node node = required(key);
      const double v = number(node, path, key, "a positive whole number of pixels");
      if (v < 1 || v > 100000 || v != std::floor(v))
        fail(path, node, key, "'" + yamlText(node) + "' is not a positive whole number of pixels");
      (std::string(key) == "width" ? c.camera.width : c.camera.height) = static_cast<int>(v);
    }
    for (const char* key : {"fx", "fy"}) {
      const YAML::Node node = required(key);
      const double v = number(node, path, key, "a positive focal length in pixels");
      if (v <= 0) fail(path, node, key, "'" + yamlText(node) + "' is not a positive focal length in pixels");
      (std::string(key) == "fx" ? c.camera.fx : c.camera.fy) = v;
    }
    c.camera.cx = number(required("cx"), path, "cx", "a finite principal point coordinate in pixels");
    c.camera.cy = number(required("cy"), path, "cy", "a finite principal point coordinate in pixels");

    const YAML::Node distortion = root["distortion"];
    const std::string accepted = c.model == CameraModel::Pinhole
                                     ? "a list [k1, k2, p1, p2, k3] (radial-tangential; or 4 values, k3 = 0)"
                                     : "a list [k1, k2, k3, k4] (equidistant)";
    if (distortion.IsDefined() && !distortion.IsNull()) {
      if (!distortion.IsSequence()) fail(path, distortion, "distortion", "expected " + accepted);
      for (const auto& item : distortion) c.distortion.push_back(number(item, path, "distortion", "a finite number"));
      const std::size_t n = c.distortion.size();
      const bool ok = c.model == CameraModel::Pinhole ? (n == 4 || n == 5) : n == 4;
      if (!ok)
        fail(path, distortion, "distortion",
             "has " + std::to_string(n) + " values; a " + (c.model == CameraModel::Pinhole ? "pinhole" : "fisheye") +
                 " camera takes " + accepted);
      if (c.model == CameraModel::Pinhole && n == 4) c.distortion.push_back(0.0);
    } else if (c.model == CameraModel::Fisheye) {
      throwAt(path, "distortion: missing (model fisheye needs " + accepted + ")");
    } else {
      c.distortion.assign(5, 0.0);
    }

    if (const YAML::Node fps = root["fps"]; fps.IsDefined() && !fps.IsNull()) {
      const double v = number(fps, path, "fps", "a positive number of frames per second");
      if (v <= 0) fail(path, fps, "fps", "'" + yamlText(fps) + "' is not a positive number of frames per second");
      c.fps = v;
    }
    if (const YAML::Node h = root["height_over_road"]; h.IsDefined() && !h.IsNull()) {
      const double v = number(h, path, "height_over_road", "a number of metres in (0, 100)");
      if (v <= 0 || v >= 100)
        fail(path, h, "height_over_road", "'" + yamlText(h) + "' is not a number of metres in (0, 100)");
      c.height_over_road = v;
    }
    return c;
  } catch (const YAML::Exception& e) {  // a shape the checks above did not foresee: still one line
    throwAt(path, "unexpected YAML structure: " + e.msg, e.mark.is_null() ? 0 : e.mark.line + 1);
  }
}

void undistortionMaps(const CameraCalibration& calibration, cv::Mat& map1, cv::Mat& map2) {
  const Camera& cam = calibration.camera;
  const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  const cv::Size size(cam.width, cam.height);
  const cv::Mat D(static_cast<int>(calibration.distortion.size()), 1, CV_64F,
                  const_cast<double*>(calibration.distortion.data()));
  if (calibration.model == CameraModel::Fisheye)
    cv::fisheye::initUndistortRectifyMap(K, D, cv::Matx33d::eye(), K, size, CV_16SC2, map1, map2);
  else
    cv::initUndistortRectifyMap(K, D, cv::noArray(), K, size, CV_16SC2, map1, map2);
}

}  // namespace beslam::datasets
