// KITTI object frame 000008 from the shared data (tests skip when it is absent).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "beslam/datasets/kitti_calib.hpp"
#include "beslam/datasets/labels.hpp"
#include "beslam/datasets/velodyne.hpp"
#include "beslam/sdk/detector.hpp"

namespace beslam::mask::fixture {

inline std::string kittiObjectDir() { return std::string(BESLAM_SHARED_DATA) + "/kitti/object/training"; }

inline bool haveKitti000008() {
  const std::string d = kittiObjectDir();
  return std::filesystem::exists(d + "/calib/000008.txt") && std::filesystem::exists(d + "/velodyne/000008.bin") &&
         std::filesystem::exists(d + "/label_2/000008.txt");
}

// A KITTI label (bottom centre) as an ABI box (geometric centre).
inline beslam_box3d boxFromLabel(const datasets::ObjectLabel& l, int id) {
  beslam_box3d b = sdk::newBox();
  b.class_id = BESLAM_CLASS_CAR;
  b.track_id = id;
  b.center_cam[0] = l.p_cam_bottom.x();
  b.center_cam[1] = l.p_cam_bottom.y() - l.h / 2;
  b.center_cam[2] = l.p_cam_bottom.z();
  b.size[0] = l.l, b.size[1] = l.w, b.size[2] = l.h;
  b.yaw = l.ry;
  return b;
}

}  // namespace beslam::mask::fixture
