// KITTI object (label_2) and tracking (label_02) label rows.
// Object row:   type truncated occluded alpha x1 y1 x2 y2 h w l x y z ry [score]          (15 or 16 fields)
// Tracking row: frame track_id type truncated occluded alpha x1 y1 x2 y2 h w l x y z ry [score]  (17/18)
// (x y z) is the bottom centre of the 3D box in the rectified reference camera frame (camera 0, the frame
// R0_rect * Tr_velo_to_cam maps LiDAR points into; metres), which P2 projects into image_2: in the camera-2
// frame of T_cam_lidar it is p_cam2 = T_cami_rect0(P2) * p (a ~6 cm x shift). ry is the yaw about the
// camera y axis; 2D boxes are in image_2 pixels. DontCare rows are kept with their type (their 3D fields are
// placeholders such as -1000). Parsers throw beslam::Error "file:line: ..." on a wrong field count or a
// non-number; formatters write the same layout (6 decimals), without a trailing newline.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace beslam::formats {

struct ObjectLabel {
  std::string type;                                        // "Car", "Pedestrian", ..., "DontCare"
  double truncated = 0;                                    // object: 0..1 fraction; tracking: 0, 1, 2
  int occluded = 0;                                        // 0 visible .. 3 unknown (-1 for DontCare)
  double alpha = 0;                                        // observation angle, radians
  double x1 = 0, y1 = 0, x2 = 0, y2 = 0;                   // 2D box, pixels
  double h = 0, w = 0, l = 0;                              // 3D box height, width, length, metres
  Eigen::Vector3d p_cam_bottom = Eigen::Vector3d::Zero();  // bottom centre, rectified camera 0 (see above)
  double ry = 0;                                           // yaw about camera y, radians
  std::optional<double> score;                             // detections only
  bool isDontCare() const { return type == "DontCare"; }
};

struct TrackingLabel {
  std::int64_t frame = 0;
  std::int64_t track_id = -1;  // -1 for DontCare
  ObjectLabel object;
};

ObjectLabel parseObjectRow(const std::string& line, const std::string& path = "<row>", int line_no = 0);
TrackingLabel parseTrackingRow(const std::string& line, const std::string& path = "<row>", int line_no = 0);

// Whole files; blank lines are skipped. Missing file -> beslam::Error naming it.
std::vector<ObjectLabel> readObjectLabels(const std::string& path);
std::vector<TrackingLabel> readTrackingLabels(const std::string& path);

// objects_motion.txt as `beslam synth` writes it: "frame track_id moving(0/1) speed_m_s" rows, '#' comments.
// Returns (frame, track id) -> moving. Missing file or a malformed row -> beslam::Error "file:line: ...".
std::map<std::pair<std::int64_t, std::int64_t>, bool> readObjectMotion(const std::string& path);

std::string formatObjectRow(const ObjectLabel& label);
std::string formatTrackingRow(const TrackingLabel& label);

}  // namespace beslam::formats
