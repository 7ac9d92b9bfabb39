// Silhouette samples of parked cars from a keyframe's label mask (the silhouette term of Algorithm 2).
//
// Contract
// - sampleSilhouettes(mask, camera, boxes, grid): for every box with a track id whose label
//   (BESLAM_LABEL_STATIC_BASE + track id) the mask holds, a grid x grid lattice of pixel centres over the
//   bounding rectangle of that label's pixels grown by a quarter of its size on each side (clipped to the
//   image). A pixel with the car's own label gives a ray that must meet the car (inside = 1); a background
//   pixel (label 0) one that must pass it (inside = 0); pixels of other objects give nothing (they may
//   hide the car). Rays are unit vectors in the camera frame through the pixel (pinhole `camera`; pixel
//   (x, y) is at image coordinates x, y, as OpenCV has it).
// - mask: CV_16UC1 of the camera's size; anything else, or grid < 2, gives no samples. Cars with no
//   inside ray give none either.
#pragma once

#include <map>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "beslam/data.h"
#include "objects/object_store.hpp"

namespace beslam::recon {

std::map<int32_t, SilhouetteSample> sampleSilhouettes(const cv::Mat& mask, const beslam_camera& camera,
                                                      const std::vector<beslam_box3d>& boxes, int grid);

}  // namespace beslam::recon
