// nuScenes detection results (the format BEVFormer and Fast-BEV write) moved into the camera frame.
//
//   {"meta": {...}, "results": {"<sample_token>": [{"sample_token": "...", "translation": [x, y, z],
//     "size": [w, l, h], "rotation": [qw, qx, qy, qz], "velocity": [vx, vy], "detection_name": "car",
//     "detection_score": 0.87, "attribute_name": "vehicle.moving"}, ...], ...}}
//
// Boxes are in the global frame (x east, y north, z up; box frame x forward along the length, z up).
// Per frame the pipeline supplies the sample token (NuScenesFrames: frame i <-> token i) and the ego pose
// T_global_ego; the camera extrinsic T_ego_cam (nuScenes calibrated_sensor: the camera's translation and
// rotation in the ego frame) is fixed. p_cam = T_ego_cam^-1 * T_global_ego^-1 * p_global; the ABI yaw is
// the heading projected onto the camera's x-z plane (ry = atan2(-h_z, h_x)); size [w l h] -> [l w h];
// velocity (absolute, over ground) is rotated into camera axes.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "beslam/data.h"
#include "beslam/detector_replay/replay.hpp"

namespace beslam::detector_replay {

// A box as nuScenes writes it (global frame).
struct NuScenesBox {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d size_wlh = Eigen::Vector3d::Ones();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  std::optional<Eigen::Vector2d> velocity;  // vx vy, global
  std::string name = "car";
  double score = 1;
};

// Global <-> camera. T_cam_global = T_ego_cam^-1 * T_global_ego^-1.
beslam_box3d cameraFromGlobal(const NuScenesBox& box, int32_t class_id, const Eigen::Isometry3d& T_cam_global);
// The inverse (the box's roll and pitch are taken as zero in the global frame: rotation about global z).
NuScenesBox globalFromCamera(const beslam_box3d& box, const Eigen::Isometry3d& T_cam_global);

// Translation + quaternion (w x y z), nuScenes' calibrated_sensor / ego_pose form, as a transform.
Eigen::Isometry3d poseFromTranslationQuaternion(const std::vector<double>& t_wxyz, const std::string& what);

// Frame index <-> sample token, with an optional ego pose per frame.
//  - a text file: one token per line (line i = frame i; blank lines and '#' comments skipped);
//  - a .json file: an array of tokens, or of objects {"token": "...", "ego_translation": [x, y, z],
//    "ego_rotation": [w, x, y, z]} (ego pose T_global_ego inline), or {"frames": <that array>}.
struct NuScenesFrames {
  std::vector<std::string> tokens;
  std::vector<std::optional<Eigen::Isometry3d>> T_global_ego;  // same length; nullopt when not given
};
NuScenesFrames readNuScenesFrames(const std::string& path);

struct NuScenesOptions {
  std::string results;  // results JSON
  NuScenesFrames frames;
  std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>> ego_poses;  // per frame, overrides
  Eigen::Isometry3d T_ego_cam = Eigen::Isometry3d::Identity();
  Filter filter;
  Policy policy = Policy::stop;
};

// Reads the results and converts every frame's boxes. A frame whose token has no entry in the results, or
// no ego pose, is not covered (the caller's missing-frame policy decides). Malformed boxes (wrong array
// sizes, non-numbers, non-positive sizes, zero quaternions, unknown detection names) are reported with
// the results file, the sample token and the box's position in its list ("results.json: sample abc, box 3:
// ..."), plus the JSON parser's line for syntax errors.
void readNuScenes(const NuScenesOptions& options, DetectionTable& table, std::vector<char>& covered, Report& report);

}  // namespace beslam::detector_replay
