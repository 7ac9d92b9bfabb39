// KITTI calibration files for the host: the SDK's formats component (beslam/formats/kitti_calib.hpp, which
// states the conventions) under the datasets namespace. Plugins include beslam/formats/kitti_calib.hpp.
#pragma once

#include "beslam/datasets/dataset.hpp"
#include "beslam/formats/kitti_calib.hpp"

namespace beslam::datasets {

using formats::CalibEntry;
using formats::cameraFromProjection;
using formats::KittiCalib;
using formats::Matrix34d;
using formats::readCalibEntries;
using formats::readObjectCalib;
using formats::readOdometryCalib;
using formats::readRawCalib;
using formats::T_cami_rect0;
using formats::T_cami_velo;

}  // namespace beslam::datasets
