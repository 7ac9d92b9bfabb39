// Trajectories for the host: the SDK's formats component (beslam/formats/trajectory.hpp) under the
// host's historical namespace. Plugins include beslam/formats/trajectory.hpp directly.
#pragma once

#include "beslam/formats/trajectory.hpp"

namespace beslam::trajectory {

using formats::detectFormat;
using formats::read;
using formats::readKitti;
using formats::readTum;
using formats::Trajectory;
using formats::writeKitti;
using formats::writeTum;

}  // namespace beslam::trajectory
