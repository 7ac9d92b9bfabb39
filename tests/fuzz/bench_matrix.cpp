// `beslam bench` matrix files (loadMatrix): a bad matrix is one beslam::Error naming the file. A matrix
// names pipeline files; the working folder (a fresh one, run_fuzzer.sh) holds pipeline.yaml, a valid
// pipeline whose backend is a plugin id no library provides, so each cell's pipeline is loaded with its
// --set overrides and then refused by the plugin registry (nothing is ever opened or run).
#include <fstream>

#include "beslam/bench/bench.hpp"
#include "beslam/common/error.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::ofstream("pipeline.yaml") << "dataset: {type: kitti_odometry, root: data, sequence: \"00\"}\n"
                                    "backend: {plugin: fuzz_no_such_backend}\n";
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "matrix.yaml");
  beslam::fuzz::acceptErrors([&] {
    const beslam::bench::Matrix m = beslam::bench::loadMatrix(path);
    // Unreachable while no plugin resolves; kept so a matrix that does load is checked too.
    for (const beslam::bench::Cell& c : beslam::bench::makeCells(m, "out"))
      beslam::fuzz::require(c.dir.find("..") == std::string::npos, "a cell folder outside the bench folder");
  });
  return 0;
}
