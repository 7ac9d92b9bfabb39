// nuScenes inputs detector_replay reads: the results JSON (per sample token, boxes in the global frame)
// and the frames file (tokens with optional ego poses). A bad file is one error naming it, never a crash
// or a JSON library exception escaping.
#include "beslam/detector_replay/nuscenes.hpp"

#include <stdexcept>

#include "fuzz_support.hpp"

namespace dr = beslam::detector_replay;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "results.json");
  try {
    dr::NuScenesOptions o;
    o.results = path;
    o.frames.tokens = {"t0", "t1", "t2"};
    o.frames.T_global_ego = {Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity(), std::nullopt};
    dr::DetectionTable table;
    std::vector<char> covered;
    dr::Report report;
    dr::readNuScenes(o, table, covered, report);
  } catch (const std::runtime_error&) {
  }
  try {
    dr::readNuScenesFrames(path);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
