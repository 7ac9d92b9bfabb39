// Checked image loading for the host: the SDK's image_io component (beslam/formats/image_io.hpp) under the
// datasets namespace. Plugins include beslam/formats/image_io.hpp and link beslam::image_io.
#pragma once

#include "beslam/formats/image_io.hpp"

namespace beslam::datasets {

using formats::checkPng;
using formats::LoadedImage;
using formats::loadImage;
using formats::readImageSize;

}  // namespace beslam::datasets
