// KITTI Velodyne scans for the host: the SDK's formats component (beslam/formats/velodyne.hpp) under the
// datasets namespace. Plugins include beslam/formats/velodyne.hpp.
#pragma once

#include "beslam/formats/velodyne.hpp"

namespace beslam::datasets {

using formats::readVelodyneBin;
using formats::writeVelodyneBin;

}  // namespace beslam::datasets
