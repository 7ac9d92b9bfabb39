// Wall time of the backend's stages (TrackResult::stage_ms, the host's timing.csv columns).
#pragma once

#include <chrono>

namespace beslam::orb {

using Clock = std::chrono::steady_clock;

inline double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace beslam::orb
