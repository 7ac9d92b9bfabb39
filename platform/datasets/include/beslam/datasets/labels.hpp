// KITTI object / tracking label rows for the host: the SDK's formats component
// (beslam/formats/labels.hpp) under the datasets namespace. Plugins include beslam/formats/labels.hpp.
#pragma once

#include "beslam/formats/labels.hpp"

namespace beslam::datasets {

using formats::formatObjectRow;
using formats::formatTrackingRow;
using formats::ObjectLabel;
using formats::parseObjectRow;
using formats::parseTrackingRow;
using formats::readObjectLabels;
using formats::readObjectMotion;
using formats::readTrackingLabels;
using formats::TrackingLabel;

}  // namespace beslam::datasets
