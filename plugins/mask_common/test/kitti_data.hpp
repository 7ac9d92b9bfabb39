// KITTI object frame 000008 from the shared data (tests skip when it is absent).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "beslam/formats/kitti_calib.hpp"
#include "beslam/formats/labels.hpp"
#include "beslam/formats/velodyne.hpp"
#include "beslam/mask_common/lidar.hpp"
#include "beslam/sdk/detector.hpp"

namespace beslam::mask::fixture {

inline std::string kittiObjectDir() { return std::string(BESLAM_SHARED_DATA) + "/kitti/object/training"; }

inline bool haveKitti000008() {
  const std::string d = kittiObjectDir();
  return std::filesystem::exists(d + "/calib/000008.txt") && std::filesystem::exists(d + "/velodyne/000008.bin") &&
         std::filesystem::exists(d + "/label_2/000008.txt");
}

// 000008's scan in rectified camera 0 (the labels' frame) with P0's intrinsics, points 0.5-120 m ahead.
struct Camera0Scan {
  Intrinsics K;
  CameraPoints pts;
};
inline Camera0Scan camera0Scan000008() {
  const std::string dir = kittiObjectDir();
  const formats::KittiCalib calib = formats::readObjectCalib(dir + "/calib/000008.txt");
  const std::vector<float> scan = formats::readVelodyneBin(dir + "/velodyne/000008.bin");
  const formats::Camera cam = formats::cameraFromProjection(*calib.P[0], 1242, 375, "P0");
  Camera0Scan out;
  out.K.fx = cam.fx, out.K.fy = cam.fy, out.K.cx = cam.cx, out.K.cy = cam.cy;
  out.K.width = cam.width, out.K.height = cam.height;
  out.pts = lidarToCamera(scan.data(), scan.size() / 4, 4, *formats::T_cami_velo(calib, 0), out.K, 0.5, 120);
  return out;
}

// A KITTI label (bottom centre) as an ABI box (geometric centre).
inline beslam_box3d boxFromLabel(const formats::ObjectLabel& l, int id) {
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
