#include "beslam/formats/kitti_calib.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string_view>

#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"
#include "beslam/formats/text.hpp"

namespace beslam::formats {
namespace {

bool contains(const std::vector<std::string>& names, const std::string& name) {
  for (const auto& n : names)
    if (n == name) return true;
  return false;
}

// The entry under the first of `names` present; its value count must be `count`.
const CalibEntry* find(const std::map<std::string, CalibEntry>& entries, const std::string& path,
                       const std::vector<std::string>& names, std::size_t count) {
  for (const auto& name : names) {
    const auto it = entries.find(name);
    if (it == entries.end()) continue;
    if (it->second.values.size() != count)
      throwAt(path,
              name + " has " + std::to_string(it->second.values.size()) + " values, expected " + std::to_string(count),
              it->second.line);
    return &it->second;
  }
  return nullptr;
}

// A number of any kind, finite or not ("nan", "-inf", "1e999"): an unnamed row that starts with one is
// a row of numbers, never a row named "nan" (which would shift every later row's name: P1 read as P0).
bool looksNumeric(std::string_view token) {
  const std::string text(token);
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size();
}

const CalibEntry& require(const std::map<std::string, CalibEntry>& entries, const std::string& path,
                          const std::vector<std::string>& names, std::size_t count) {
  if (const CalibEntry* e = find(entries, path, names, count)) return *e;
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : " or ") + n;
  throwAt(path, "missing calibration entry " + list);
}

Matrix34d toMatrix34(const CalibEntry& e) {
  Matrix34d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = e.values[static_cast<std::size_t>(r * 4 + c)];
  return m;
}

Eigen::Matrix3d toMatrix3(const CalibEntry& e, std::size_t offset = 0, std::size_t stride = 3) {
  Eigen::Matrix3d m;
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 3; ++c) m(r, c) = e.values[offset + r * stride + c];
  return m;
}

void checkRotation(const Eigen::Matrix3d& R, const std::string& path, const std::string& name, int line) {
  const double error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(error < 1e-3) || !(R.determinant() > 0))
    throwAt(path, name + " is not a rotation (|R^T R - I| = " + std::to_string(error) + ")", line);
}

Eigen::Isometry3d toIsometry(const CalibEntry& e, const std::string& path, const std::string& name) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = toMatrix3(e, 0, 4);
  T.translation() << e.values[3], e.values[7], e.values[11];
  checkRotation(T.linear(), path, name, e.line);
  return T;
}

void checkProjection(const Matrix34d& P, const std::string& path, const std::string& name, int line) {
  (void)cameraFromProjection(P, 0, 0, path + (line > 0 ? ":" + std::to_string(line) : "") + ": " + name);
}

}  // namespace

std::map<std::string, CalibEntry> readCalibEntries(const std::string& path, const std::vector<std::string>& bare_names,
                                                   const std::vector<std::string>& text_keys) {
  const std::string text = readFile(path);
  std::map<std::string, CalibEntry> entries;
  std::size_t bare_rows = 0;
  const auto lines = splitLines(text);
  for (std::size_t li = 0; li < lines.size(); ++li) {
    const int line_no = static_cast<int>(li + 1);
    auto tokens = splitWhitespace(lines[li]);
    if (tokens.empty() || tokens.front().front() == '#') continue;  // blank or comment
    std::string name;
    std::size_t first_value = 0;
    double probe = 0;
    const std::string_view head = tokens.front();
    const std::size_t colon = head.find(':');
    if (colon != std::string_view::npos) {
      name = std::string(head.substr(0, colon));
      if (colon + 1 < head.size())
        tokens.front() = head.substr(colon + 1);  // "P0:7.1e+02"
      else
        first_value = 1;
    } else if (parseDouble(head, probe) || looksNumeric(head)) {
      if (bare_rows >= bare_names.size())
        throwAt(path,
                "unnamed row " + std::to_string(bare_rows + 1) + " (expected at most " +
                    std::to_string(bare_names.size()) + " unnamed rows)",
                line_no);
      name = bare_names[bare_rows++];
    } else {
      name = std::string(head);  // tracking style: "R_rect 9.99e-01 ..."
      first_value = 1;
    }
    if (name.empty()) throwAt(path, "row without a name before ':'", line_no);
    if (entries.count(name)) throwAt(path, "duplicate calibration entry " + name, line_no);
    CalibEntry entry;
    entry.line = line_no;
    if (contains(text_keys, name)) {
      const std::size_t pos = lines[li].find(':');
      entry.text = std::string(pos == std::string_view::npos ? lines[li] : lines[li].substr(pos + 1));
    } else {
      for (std::size_t t = first_value; t < tokens.size(); ++t) {
        double v = 0;
        if (!parseDouble(tokens[t], v))
          throwAt(path,
                  "'" + std::string(tokens[t]) + "' in " + name + " is not a " +
                      (looksNumeric(tokens[t]) ? "finite number" : "number"),
                  line_no);
        entry.values.push_back(v);
      }
      if (entry.values.empty()) throwAt(path, name + " has no values", line_no);
    }
    entries.emplace(name, std::move(entry));
  }
  if (entries.empty()) throwAt(path, "empty calibration file");
  return entries;
}

namespace {

// A calibration of `path` with the projections P0..P3 from the entries prefix + "0" .. prefix + "3" (each
// checked); all four must be there when `required`, else those present are taken.
KittiCalib withProjections(const std::map<std::string, CalibEntry>& entries, const std::string& path,
                           const std::string& prefix, bool required) {
  KittiCalib calib;
  calib.path = path;
  for (int i = 0; i < 4; ++i) {
    const std::string name = prefix + std::to_string(i);
    const CalibEntry* e = required ? &require(entries, path, {name}, 12) : find(entries, path, {name}, 12);
    if (!e) continue;
    calib.P[static_cast<std::size_t>(i)] = toMatrix34(*e);
    checkProjection(toMatrix34(*e), path, name, e->line);
  }
  return calib;
}

}  // namespace

KittiCalib readOdometryCalib(const std::string& path) {
  const auto entries = readCalibEntries(path, {"P0", "P1", "P2", "P3", "Tr"});
  KittiCalib calib = withProjections(entries, path, "P", false);
  if (!calib.P[0]) throwAt(path, "missing calibration entry P0");
  if (const CalibEntry* e = find(entries, path, {"Tr", "Tr_velo_to_cam"}, 12))
    calib.T_cam0_velo = toIsometry(*e, path, "Tr");
  return calib;
}

KittiCalib readObjectCalib(const std::string& path) {
  const auto entries = readCalibEntries(path);
  KittiCalib calib = withProjections(entries, path, "P", true);
  const CalibEntry& r0 = require(entries, path, {"R0_rect", "R_rect"}, 9);
  calib.R0_rect = toMatrix3(r0);
  checkRotation(calib.R0_rect, path, "R0_rect", r0.line);
  if (const CalibEntry* e = find(entries, path, {"Tr_velo_to_cam", "Tr_velo_cam"}, 12))
    calib.T_cam0_velo = toIsometry(*e, path, "Tr_velo_to_cam");
  if (const CalibEntry* e = find(entries, path, {"Tr_imu_to_velo", "Tr_imu_velo"}, 12))
    calib.T_velo_imu = toIsometry(*e, path, "Tr_imu_to_velo");
  return calib;
}

KittiCalib readRawCalib(const std::string& cam_to_cam_path, const std::string& velo_to_cam_path) {
  const auto cam = readCalibEntries(cam_to_cam_path, {}, {"calib_time"});
  KittiCalib calib = withProjections(cam, cam_to_cam_path, "P_rect_0", false);
  const CalibEntry& r0 = require(cam, cam_to_cam_path, {"R_rect_00"}, 9);
  calib.R0_rect = toMatrix3(r0);
  checkRotation(calib.R0_rect, cam_to_cam_path, "R_rect_00", r0.line);
  if (!velo_to_cam_path.empty() && std::filesystem::exists(velo_to_cam_path)) {
    const auto velo = readCalibEntries(velo_to_cam_path, {}, {"calib_time"});
    const CalibEntry& R = require(velo, velo_to_cam_path, {"R"}, 9);
    const CalibEntry& T = require(velo, velo_to_cam_path, {"T"}, 3);
    Eigen::Isometry3d T_cam0_velo = Eigen::Isometry3d::Identity();
    T_cam0_velo.linear() = toMatrix3(R);
    checkRotation(T_cam0_velo.linear(), velo_to_cam_path, "R", R.line);
    T_cam0_velo.translation() << T.values[0], T.values[1], T.values[2];
    calib.T_cam0_velo = T_cam0_velo;
    calib.path += " + " + velo_to_cam_path;
  }
  return calib;
}

Camera cameraFromProjection(const Matrix34d& P, int width, int height, const std::string& what) {
  const double fx = P(0, 0), fy = P(1, 1);
  if (!(std::isfinite(fx) && fx > 0) || !(std::isfinite(fy) && fy > 0))
    throw Error(what + ": focal lengths must be finite and positive (fx " + std::to_string(fx) + ", fy " +
                std::to_string(fy) + ")");
  const double tol = 1e-9 * std::max(1.0, std::abs(fx));
  if (!(fx > 0) || !(fy > 0) || std::abs(P(0, 1)) > tol || std::abs(P(1, 0)) > tol || std::abs(P(2, 0)) > 1e-12 ||
      std::abs(P(2, 1)) > 1e-12 || std::abs(P(2, 2) - 1.0) > 1e-12)
    throw Error(what + ": not a rectified pinhole projection (expected [fx 0 cx tx; 0 fy cy ty; 0 0 1 tz])");
  Camera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = fx;
  camera.fy = fy;
  camera.cx = P(0, 2);
  camera.cy = P(1, 2);
  return camera;
}

Eigen::Isometry3d T_cami_rect0(const Matrix34d& P_i) {
  const Eigen::Matrix3d K = P_i.leftCols<3>();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = K.triangularView<Eigen::Upper>().solve(P_i.col(3));
  return T;
}

std::optional<Eigen::Isometry3d> T_cami_velo(const KittiCalib& calib, int camera_index) {
  if (camera_index < 0 || camera_index > 3) return std::nullopt;
  const auto& P = calib.P[static_cast<std::size_t>(camera_index)];
  if (!P || !calib.T_cam0_velo) return std::nullopt;
  Eigen::Isometry3d T_rect0_cam0 = Eigen::Isometry3d::Identity();
  T_rect0_cam0.linear() = calib.R0_rect;
  return T_cami_rect0(*P) * T_rect0_cam0 * *calib.T_cam0_velo;
}

}  // namespace beslam::formats
