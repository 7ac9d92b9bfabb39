// The pipeline loader on arbitrary YAML: every bad file must be one beslam::Error, nothing else.
#include "beslam/common/error.hpp"
#include "beslam/pipeline/spec.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "pipeline.yaml");
  beslam::fuzz::acceptErrors([&] { beslam::pipeline::loadPipeline(path); });
  return 0;
}
