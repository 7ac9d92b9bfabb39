// Camera: the image size and intrinsics of a rectified (or undistorted) pinhole camera, in pixels:
// u = fx * x / z + cx, v = fy * y / z + cy for a point (x, y, z) in the camera frame (x right, y down,
// z forward). KITTI's projections give one (kitti_calib.hpp: cameraFromProjection); the host's datasets
// report theirs as this type.
#pragma once

namespace beslam::formats {

struct Camera {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

}  // namespace beslam::formats
