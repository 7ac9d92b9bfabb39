// KITTI Velodyne scans (.bin, float32 x y z reflectance): the reader, then what the host hands a scan to
// first, mask_lidar's geometry (the scan into the camera, the box fine-tuned to its points in the bird's-eye
// view, the per-object point mask). A bad file is one beslam::Error naming the file; a scan that is read
// has one value per 4 input bytes, and the masks made with it fit their boxes' crops, the boxes finite.
//
// Seeds (corpus/velodyne/): the points around one parked car of a `beslam synth` scan (make_velodyne_seed.py),
// the car being the box below.
#include "beslam/datasets/velodyne.hpp"

#include <cmath>

#include "beslam/common/error.hpp"
#include "beslam/mask_common/mask_builder.hpp"
#include "fuzz_support.hpp"

namespace {

// The synthetic KITTI-like camera and LiDAR mount (beslam synth's calib.txt: P2, Tr_velo_to_cam).
const beslam::mask::MaskBuilder& builder() {
  static const beslam::mask::MaskBuilder b = [] {
    beslam::mask::Intrinsics K;
    K.fx = K.fy = 718.856;
    K.cx = 607.1928;
    K.cy = 185.2157;
    K.width = 1241;
    K.height = 376;
    Eigen::Isometry3d T_cam_lidar = Eigen::Isometry3d::Identity();
    T_cam_lidar.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
    T_cam_lidar.translation() = Eigen::Vector3d(0, -0.08, -0.27);
    beslam::mask::MaskOptions o;
    o.use_lidar = true;
    o.contour = false;  // needs the image; the fuzz input is the scan
    o.bev.intrinsics = K;
    return beslam::mask::MaskBuilder(K, T_cam_lidar, o);
  }();
  return b;
}

// The parked car of the seed scan (label_02 of frame 0, track 17), centre = KITTI location - height / 2.
beslam_box3d car() {
  beslam_box3d box{};
  box.class_id = BESLAM_CLASS_CAR;
  box.track_id = 17;
  box.motion_state = BESLAM_MOTION_STATIC;
  box.center_cam[0] = 2.726251;
  box.center_cam[1] = 1.646015 - 1.527938 / 2;
  box.center_cam[2] = 17.150265;
  box.size[0] = 4.612504;
  box.size[1] = 1.840102;
  box.size[2] = 1.527938;
  box.yaw = -1.573796;
  box.score = 1;
  return box;
}

bool finite(const beslam_box3d& b) {
  for (double v : {b.center_cam[0], b.center_cam[1], b.center_cam[2], b.size[0], b.size[1], b.size[2], b.yaw})
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "scan.bin");
  std::vector<float> scan;
  try {
    scan = beslam::datasets::readVelodyneBin(path);
  } catch (const beslam::Error&) {
    return 0;
  }
  beslam::fuzz::require(scan.size() * sizeof(float) == size, "a scan of another size than its file");
  const beslam_point_cloud_view view{scan.empty() ? nullptr : scan.data(), scan.size() / 4, 16, 0};
  for (const beslam::mask::ObjectMask& o : builder().objects(cv::Mat(), view, {car()})) {
    beslam::fuzz::require(finite(o.box), "a refined box that is not finite");
    beslam::fuzz::require(o.mask.empty() || (o.mask.cols == o.roi.width && o.mask.rows == o.roi.height),
                          "an object mask of another size than its crop");
  }
  return 0;
}
