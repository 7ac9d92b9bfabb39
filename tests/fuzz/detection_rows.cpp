// The detection files detector_replay reads (AB3DMOT rows, KITTI tracking and object label files): a bad
// file is one error naming the file and line (std::runtime_error, beslam::Error among them).
#include <stdexcept>

#include "beslam/detector_replay/replay.hpp"
#include "fuzz_support.hpp"

namespace dr = beslam::detector_replay;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "detections.txt");
  for (dr::ScoreTransform transform : {dr::ScoreTransform::none, dr::ScoreTransform::sigmoid}) {
    for (dr::Policy policy : {dr::Policy::stop, dr::Policy::skip}) {
      dr::Filter filter;
      try {
        dr::DetectionTable table;
        dr::Report report;
        dr::readAb3dmotFile(path, filter, policy, transform, table, report);
      } catch (const std::runtime_error&) {
      }
      try {
        dr::DetectionTable table;
        dr::Report report;
        dr::readKittiTrackingFile(path, filter, policy, transform, table, report);
      } catch (const std::runtime_error&) {
      }
      try {
        dr::DetectionTable table;
        dr::Report report;
        dr::readKittiObjectFile(path, 0, filter, policy, transform, table, report);
      } catch (const std::runtime_error&) {
      }
    }
  }
  return 0;
}
