// The pipeline loader on arbitrary YAML: every bad file must be one beslam::Error, nothing else.
#include "beslam/common/error.hpp"
#include "beslam/pipeline/spec.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "pipeline.yaml");
  try {
    beslam::pipeline::loadPipeline(path);
  } catch (const beslam::Error&) {
  }
  return 0;
}
