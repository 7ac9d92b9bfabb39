// PLY meshes (objects/*.ply, map.ply, the shape-prior tools' meshes): bad files are one beslam::Error.
#include "beslam/formats/error.hpp"
#include "beslam/formats/ply.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = beslam::fuzz::writeScratch(data, size, "mesh.ply");
  beslam::fuzz::acceptErrors([&] { beslam::formats::readPlyMesh(path); });
  return 0;
}
