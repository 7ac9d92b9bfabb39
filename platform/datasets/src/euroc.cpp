// EuRoC / ASL (type euroc): <root>/mav0 (or root = mav0 itself) with
//   cam0/data.csv                        "#timestamp [ns],filename" then "1403636579763555584,1403636579763555584.png"
//   cam0/data/*.png                      the images
//   cam0/sensor.yaml                     intrinsics [fu, fv, cu, cv], distortion_model (radial-tangential |
//                                        equidistant), distortion_coefficients, resolution [w, h], rate_hz, T_BS
//                                        (camera -> body, 4x4 row-major in data)
//   state_groundtruth_estimate0/data.csv optional: t [ns], p_RS_R xyz, q_RS_R wxyz, ... (T_world_body)
// A camera file (options.calibration) replaces sensor.yaml's camera; T_BS is always sensor.yaml's. Ground
// truth is T_world_cam = T_world_body * T_BS at each frame's time (interpolated like TUM's).
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/yaml_load.hpp"
#include "beslam/datasets/image_io.hpp"
#include "beslam/datasets/tum.hpp"
#include "dataset_impl.hpp"
#include "parse_util.hpp"

namespace beslam::datasets::detail {
namespace {

struct EurocSensor {
  CameraCalibration calibration;
  Eigen::Isometry3d T_body_cam = Eigen::Isometry3d::Identity();  // T_BS
};

std::string trim(std::string_view text) {
  const auto b = text.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  const auto e = text.find_last_not_of(" \t\r");
  return std::string(text.substr(b, e - b + 1));
}

std::vector<std::string> splitCommas(std::string_view line) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(
        trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

std::vector<double> numbers(const YAML::Node& node, const std::string& path, const std::string& key, std::size_t n,
                            const std::string& accepted) {
  const std::string where = yamlWhere(path, node);
  if (!node.IsDefined() || node.IsNull()) throwAt(path, key + ": missing (expected " + accepted + ")");
  if (!node.IsSequence() || (n > 0 && node.size() != n)) throw Error(where + ": " + key + ": expected " + accepted);
  std::vector<double> values;
  for (const auto& item : node) {
    double v = 0;
    if (!item.IsScalar() || !YAML::convert<double>::decode(item, v) || !std::isfinite(v))
      throw Error(where + ": " + key + ": '" + (item.IsScalar() ? item.Scalar() : std::string("?")) +
                  "' is not a finite number (expected " + accepted + ")");
    values.push_back(v);
  }
  return values;
}

// cam0/sensor.yaml (OpenCV-style "%YAML:1.0" first line allowed).
EurocSensor readSensorYaml(const std::string& path) {
  std::string text = readFile(path);
  if (text.rfind("%YAML", 0) == 0) text = text.substr(std::min(text.size(), text.find('\n')));  // OpenCV's directive
  YAML::Node root = loadYaml(text, path);  // the checks of beslam/common/yaml_load.hpp
  if (!root.IsMap()) throwAt(path, "expected a map (EuRoC sensor.yaml: intrinsics, resolution, T_BS, ...)");
  try {
    EurocSensor s;
    CameraCalibration& c = s.calibration;
    c.source = path;
    if (const YAML::Node model = root["camera_model"];
        model.IsDefined() && !(model.IsScalar() && model.Scalar() == "pinhole"))
      throwAt(path, "camera_model: '" + (model.IsScalar() ? model.Scalar() : std::string("?")) +
                        "' is not supported (accepted: pinhole; or give dataset.calibration)");
    const auto K = numbers(root["intrinsics"], path, "intrinsics", 4, "[fu, fv, cu, cv]");
    if (!(K[0] > 0 && K[1] > 0)) throwAt(path, "intrinsics: focal lengths fu, fv must be positive");
    c.camera.fx = K[0], c.camera.fy = K[1], c.camera.cx = K[2], c.camera.cy = K[3];
    const auto res = numbers(root["resolution"], path, "resolution", 2, "[width, height] in pixels");
    if (!(res[0] >= 1 && res[1] >= 1 && res[0] == std::floor(res[0]) && res[1] == std::floor(res[1])))
      throwAt(path, "resolution: expected [width, height], two positive whole numbers of pixels");
    c.camera.width = static_cast<int>(res[0]), c.camera.height = static_cast<int>(res[1]);
    const YAML::Node model_node = root["distortion_model"];
    const std::string model = model_node.IsScalar() ? model_node.Scalar() : "radial-tangential";
    if (model == "radial-tangential" || model == "radtan") {
      c.model = CameraModel::Pinhole;
      c.distortion = numbers(root["distortion_coefficients"], path, "distortion_coefficients", 0,
                             "[k1, k2, p1, p2] or [k1, k2, p1, p2, k3]");
      if (c.distortion.size() != 4 && c.distortion.size() != 5)
        throwAt(path, "distortion_coefficients: has " + std::to_string(c.distortion.size()) +
                          " values; radial-tangential takes [k1, k2, p1, p2] or [k1, k2, p1, p2, k3]");
      c.distortion.resize(5, 0.0);
    } else if (model == "equidistant") {
      c.model = CameraModel::Fisheye;
      c.distortion = numbers(root["distortion_coefficients"], path, "distortion_coefficients", 4, "[k1, k2, k3, k4]");
    } else {
      throwAt(path, "distortion_model: '" + model + "' is not supported (accepted: radial-tangential, equidistant)");
    }
    if (const YAML::Node rate = root["rate_hz"]; rate.IsDefined()) {
      double v = 0;
      if (!rate.IsScalar() || !YAML::convert<double>::decode(rate, v) || !(v > 0) || !std::isfinite(v))
        throwAt(path, "rate_hz: expected a positive number of frames per second");
      c.fps = v;
    }
    const YAML::Node T = root["T_BS"];
    if (!T.IsMap()) throwAt(path, "T_BS: missing (expected {cols: 4, rows: 4, data: [16 numbers, row-major]})");
    const auto data = numbers(T["data"], path, "T_BS.data", 16, "16 numbers, a 4x4 row-major transform");
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r)
      for (int col = 0; col < 4; ++col) M(r, col) = data[static_cast<std::size_t>(4 * r + col)];
    const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
    if ((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-3 || R.determinant() < 0 ||
        (M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9)
      throwAt(path, "T_BS: data is not a rigid transform (rotation rows orthonormal, last row 0 0 0 1)");
    Eigen::Quaterniond q(R);
    s.T_body_cam.linear() = q.normalized().toRotationMatrix();
    s.T_body_cam.translation() = M.topRightCorner<3, 1>();
    return s;
  } catch (const YAML::Exception& e) {
    throwAt(path, "unexpected YAML structure: " + e.msg, e.mark.is_null() ? 0 : e.mark.line + 1);
  }
}

}  // namespace

trajectory::Trajectory readEurocGroundTruth(const std::string& path) {
  const std::string text = readFile(path);
  const auto lines = splitLines(text);
  trajectory::Trajectory gt;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (isBlank(lines[i]) || trim(lines[i]).front() == '#') continue;
    const int line_no = static_cast<int>(i + 1);
    const auto fields = splitCommas(lines[i]);
    if (fields.size() < 8)
      throwAt(
          path,
          "expected at least 8 comma-separated values (t [ns], p xyz, q wxyz), got " + std::to_string(fields.size()),
          line_no);
    std::int64_t ns = 0;
    if (!parseInt(fields[0], ns)) throwAt(path, "'" + fields[0] + "' is not a timestamp in nanoseconds", line_no);
    double v[7];
    for (int k = 0; k < 7; ++k)
      if (!parseDouble(fields[static_cast<std::size_t>(k + 1)], v[k]) || !std::isfinite(v[k]))
        throwAt(path, "'" + fields[static_cast<std::size_t>(k + 1)] + "' is not a number", line_no);
    const Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
    if (!(q.norm() > 0.5 && q.norm() < 1.5)) throwAt(path, "quaternion q_wxyz is not of unit length", line_no);
    const double t = static_cast<double>(ns) * 1e-9;
    if (!gt.stamps.empty() && t <= gt.stamps.back()) throwAt(path, "timestamps are not increasing", line_no);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    gt.push_back(t, T);
  }
  if (gt.size() == 0) throwAt(path, "holds no poses");
  return gt;
}

std::unique_ptr<Dataset> openEuroc(const DatasetOptions& options) {
  requireDirectory(options.root, "EuRoC");
  if (!options.ego_poses.empty())
    throw Error("dataset options: ego_poses is not supported for euroc (state_groundtruth_estimate0 is read)");
  if (!options.camera.empty() && options.camera != "auto")
    throw Error("dataset options: euroc reads cam0; camera must be auto (got '" + options.camera + "')");
  const std::string mav = isDirectory(joinPath(options.root, "cam0")) ? options.root : joinPath(options.root, "mav0");
  const std::string cam_dir = joinPath(mav, "cam0");
  if (!isDirectory(cam_dir))
    throwAt(cam_dir,
            "missing camera folder (EuRoC/ASL layout: mav0/cam0/data.csv, mav0/cam0/data/*.png, "
            "mav0/cam0/sensor.yaml)");
  const std::string csv = joinPath(cam_dir, "data.csv");
  requireFile(csv, "image list data.csv (\"#timestamp [ns],filename\" rows)");
  const std::string sensor_path = joinPath(cam_dir, "sensor.yaml");
  requireFile(sensor_path, "camera description sensor.yaml (intrinsics, distortion, resolution, T_BS)");
  const EurocSensor sensor = readSensorYaml(sensor_path);

  std::vector<FrameEntry> all;
  const std::string image_dir = joinPath(cam_dir, "data");
  const std::string csv_text = readFile(csv);
  const auto lines = splitLines(csv_text);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (isBlank(lines[i]) || trim(lines[i]).front() == '#') continue;
    const int line_no = static_cast<int>(i + 1);
    const auto fields = splitCommas(lines[i]);
    std::int64_t ns = 0;
    if (fields.size() != 2 || fields[1].empty())
      throwAt(csv, "expected 'timestamp [ns],filename', got '" + std::string(lines[i]) + "'", line_no);
    if (!parseInt(fields[0], ns)) throwAt(csv, "'" + fields[0] + "' is not a timestamp in nanoseconds", line_no);
    FrameEntry f;
    f.index = static_cast<std::int64_t>(all.size());
    f.timestamp = static_cast<double>(ns) * 1e-9;
    if (!all.empty() && f.timestamp <= all.back().timestamp) throwAt(csv, "timestamps are not increasing", line_no);
    f.image_path = joinPath(image_dir, fields[1]);
    all.push_back(std::move(f));
  }
  if (all.empty()) throwAt(csv, "lists no images");
  std::vector<std::int64_t> indices(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) indices[k] = static_cast<std::int64_t>(k);

  DatasetContents c;
  for (std::size_t p : selectFrames(indices, options, csv)) {
    requireFile(all[p].image_path, "image (listed in " + csv + ")");
    c.frames.push_back(all[p]);
  }
  const CameraCalibration calibration =
      options.calibration.empty() ? sensor.calibration : readCameraFile(options.calibration);
  const std::string& first = c.frames.front().image_path;
  const std::string camera_text = useCalibration(c, calibration, readImageSize(first), first);

  std::string gt_text;
  const std::string gt_path = joinPath(joinPath(mav, "state_groundtruth_estimate0"), "data.csv");
  if (isFile(gt_path)) {
    const trajectory::Trajectory T_world_body = readEurocGroundTruth(gt_path);
    trajectory::Trajectory selected;
    for (const FrameEntry& f : c.frames)
      if (const auto T = poseAt(T_world_body, f.timestamp, options.gt_max_dt))
        selected.push_back(f.timestamp, *T * sensor.T_body_cam);
    gt_text =
        ", ground truth for " + std::to_string(selected.size()) + "/" + std::to_string(c.frames.size()) + " frames";
    c.ground_truth = std::move(selected);
  }
  c.load_color = options.load_color;
  std::filesystem::path normal = std::filesystem::absolute(options.root).lexically_normal();
  if (normal.filename().empty()) normal = normal.parent_path();
  c.description = "EuRoC " + normal.filename().string() + " (" + std::to_string(c.frames.size()) + " frames, cam0" +
                  camera_text + rangeText(options, c.frames, all.size()) + gt_text + ")";
  return std::make_unique<LoadedDataset>(std::move(c));
}

}  // namespace beslam::datasets::detail
