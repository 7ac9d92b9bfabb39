// objects.txt rows: one KITTI tracking row per box plus the detector score and the motion state:
//   frame track_id type truncated occluded alpha x1 y1 x2 y2 h w l x y z ry score state
// with x y z the bottom centre in the camera frame (KITTI), the 2D box from the detector or else the
// clipped projection of the 3D box, and state one of static / dynamic / unknown.
#pragma once

#include <string>

#include "beslam/data.h"

namespace beslam::pipeline {

// The image rectangle [u0, v0, u1, v1] of the box's corners in front of the camera, clipped to the
// image; all -1 when no corner is in front.
void projectBox(const beslam_box3d& box, const beslam_camera& camera, double bbox[4]);

std::string formatObjectRow(int64_t frame_index, const beslam_box3d& box, const beslam_camera& camera);

}  // namespace beslam::pipeline
