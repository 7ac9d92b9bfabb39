// KITTI calibration files and the camera / LiDAR geometry derived from them.
// Conventions: P_i (3x4) projects a point in rectified camera-0 coordinates into image i; P_i = K_i [I | t_i]
// with t_i the offset of camera i from camera 0 (P_i[0,3] = -baseline * fx for a right camera).
// R0_rect maps unrectified camera-0 coordinates into rectified ones; T_cam0_velo (Tr_velo_to_cam) maps
// LiDAR coordinates into unrectified camera 0 (odometry's Tr already lands in the rectified frame, so R0 is
// the identity there). The composed T_cami_velo = [I | t_i] * R0_rect * T_cam0_velo satisfies
// K_i * (T_cami_velo * p_velo) == P_i * R0_rect * Tr * p_velo (up to scale).
// Parsers throw beslam::Error "file:line: ..." on a row with the wrong number of values or a non-number,
// and "file: ..." when a required entry is missing.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "beslam/formats/camera.hpp"

namespace beslam::formats {

using Matrix34d = Eigen::Matrix<double, 3, 4>;

struct KittiCalib {
  std::string path;                           // the file(s) it came from, for messages
  std::array<std::optional<Matrix34d>, 4> P;  // P0..P3 (P_rect_00..03 for raw), absent if not in the file
  Eigen::Matrix3d R0_rect = Eigen::Matrix3d::Identity();
  std::optional<Eigen::Isometry3d> T_cam0_velo;  // Tr / Tr_velo_to_cam / Tr_velo_cam / R|T of raw
  std::optional<Eigen::Isometry3d> T_velo_imu;   // Tr_imu_to_velo / Tr_imu_velo, if present
};

// One "NAME: v v v" / "NAME v v v" / bare "v v v" row set. Bare rows take the name at their row position
// from bare_names (error if there are more rows). Keys in text_keys (e.g. "calib_time") are kept unparsed.
struct CalibEntry {
  std::vector<double> values;
  std::string text;  // raw value text (text keys only)
  int line = 0;
};
std::map<std::string, CalibEntry> readCalibEntries(const std::string& path,
                                                   const std::vector<std::string>& bare_names = {},
                                                   const std::vector<std::string>& text_keys = {});

// Odometry calib.txt: P0..P3 and Tr, named ("P0: ...") or bare rows in that order. P0 is required.
KittiCalib readOdometryCalib(const std::string& path);

// Object (P0-P3, R0_rect, Tr_velo_to_cam, Tr_imu_to_velo) and tracking (R_rect, Tr_velo_cam, Tr_imu_velo,
// names with or without ':') calibration. P0..P3 and R0_rect are required, the transforms optional.
KittiCalib readObjectCalib(const std::string& path);

// Raw: calib_cam_to_cam.txt (P_rect_0X, R_rect_00) and calib_velo_to_cam.txt (R, T; optional file).
KittiCalib readRawCalib(const std::string& cam_to_cam_path, const std::string& velo_to_cam_path);

// Intrinsics of P (zero skew, last row [0 0 1 *] required); throws beslam::Error naming `what` otherwise.
Camera cameraFromProjection(const Matrix34d& P, int width, int height, const std::string& what);

// T_cami_rect0: rectified camera 0 -> rectified camera i, [I | K_i^-1 * P_i[:,3]].
Eigen::Isometry3d T_cami_rect0(const Matrix34d& P_i);

// LiDAR -> rectified camera i; nullopt when the calibration has no LiDAR transform or no P_i.
std::optional<Eigen::Isometry3d> T_cami_velo(const KittiCalib& calib, int camera_index);

}  // namespace beslam::formats
