#include "beslam/pipeline/objects.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "beslam/datasets/labels.hpp"
#include "beslam/sdk/views.hpp"

namespace beslam::pipeline {

namespace {

double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

}  // namespace

void projectBox(const beslam_box3d& box, const beslam_camera& camera, double bbox[4]) {
  const Eigen::Matrix<double, 3, 8> corners_cam = sdk::boxCorners(box);
  double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
  bool any = false;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d p_cam = corners_cam.col(i);
    if (p_cam.z() < 0.1) continue;
    const double u = camera.fx * p_cam.x() / p_cam.z() + camera.cx;
    const double v = camera.fy * p_cam.y() / p_cam.z() + camera.cy;
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    any = true;
  }
  if (!any) {
    bbox[0] = bbox[1] = bbox[2] = bbox[3] = -1;
    return;
  }
  const double W = camera.width > 0 ? camera.width - 1 : 1e9, H = camera.height > 0 ? camera.height - 1 : 1e9;
  bbox[0] = std::clamp(u0, 0.0, W);
  bbox[1] = std::clamp(v0, 0.0, H);
  bbox[2] = std::clamp(u1, 0.0, W);
  bbox[3] = std::clamp(v1, 0.0, H);
}

std::string formatObjectRow(int64_t frame_index, const beslam_box3d& box, const beslam_camera& camera) {
  datasets::TrackingLabel label;
  label.frame = frame_index;
  label.track_id = box.track_id;
  datasets::ObjectLabel& o = label.object;
  o.type = sdk::className(box.class_id);
  o.truncated = box.truncation;
  o.occluded = box.occlusion;
  double bbox[4] = {-1, -1, -1, -1};
  if (box.flags & BESLAM_BOX_HAS_BBOX2D)
    std::copy(box.bbox2d, box.bbox2d + 4, bbox);
  else
    projectBox(box, camera, bbox);
  o.x1 = bbox[0], o.y1 = bbox[1], o.x2 = bbox[2], o.y2 = bbox[3];
  o.l = box.size[0], o.w = box.size[1], o.h = box.size[2];
  o.p_cam_bottom = Eigen::Vector3d(box.center_cam[0], box.center_cam[1] + box.size[2] / 2, box.center_cam[2]);
  o.ry = box.yaw;
  o.alpha = wrapAngle(box.yaw - std::atan2(o.p_cam_bottom.x(), o.p_cam_bottom.z()));
  o.score = box.score;
  return datasets::formatTrackingRow(label) + " " + sdk::motionName(box.motion_state);
}

}  // namespace beslam::pipeline
