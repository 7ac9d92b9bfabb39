#include "beslam/pipeline/objects.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Geometry>

namespace beslam::pipeline {

namespace {

const char* typeName(int32_t class_id) {
  switch (class_id) {
    case BESLAM_CLASS_CAR: return "Car";
    case BESLAM_CLASS_PEDESTRIAN: return "Pedestrian";
    case BESLAM_CLASS_CYCLIST: return "Cyclist";
    case BESLAM_CLASS_TRUCK: return "Truck";
    case BESLAM_CLASS_VAN: return "Van";
    default: return "Misc";
  }
}

const char* stateName(int32_t state) {
  switch (state) {
    case BESLAM_MOTION_STATIC: return "static";
    case BESLAM_MOTION_DYNAMIC: return "dynamic";
    default: return "unknown";
  }
}

double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

// The image rectangle of the box's corners in front of the camera, clipped to the image.
void projectBox(const beslam_box3d& box, const beslam_camera& camera, double bbox[4]) {
  const double l = box.size[0] / 2, w = box.size[1] / 2, h = box.size[2] / 2;
  const Eigen::Matrix3d R_cam_box = Eigen::AngleAxisd(box.yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d c(box.center_cam[0], box.center_cam[1], box.center_cam[2]);
  double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
  bool any = false;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d p_box((i & 1) ? l : -l, (i & 2) ? h : -h, (i & 4) ? w : -w);
    const Eigen::Vector3d p_cam = R_cam_box * p_box + c;
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

}  // namespace

std::string formatObjectRow(int64_t frame_index, const beslam_box3d& box, const beslam_camera& camera) {
  double bbox[4] = {-1, -1, -1, -1};
  if (box.flags & BESLAM_BOX_HAS_BBOX2D)
    std::copy(box.bbox2d, box.bbox2d + 4, bbox);
  else
    projectBox(box, camera, bbox);
  const double x = box.center_cam[0], y_bottom = box.center_cam[1] + box.size[2] / 2, z = box.center_cam[2];
  const double alpha = wrapAngle(box.yaw - std::atan2(x, z));
  char row[512];
  std::snprintf(row, sizeof(row),
                "%lld %d %s %.2f %d %.6f %.2f %.2f %.2f %.2f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %s",
                static_cast<long long>(frame_index), box.track_id, typeName(box.class_id), box.truncation,
                box.occlusion, alpha, bbox[0], bbox[1], bbox[2], bbox[3], box.size[2], box.size[1], box.size[0], x,
                y_bottom, z, box.yaw, static_cast<double>(box.score), stateName(box.motion_state));
  return row;
}

}  // namespace beslam::pipeline
