// backend_orb's map files (`--load-map`): a bad file is one std::runtime_error "map file '<path>': ..." and
// the map untouched; a file that loads saves again and that file loads to the same counts.
//
// The format ends in a checksum of the payload, which random bytes never match; so each input is tried
// twice: as it is (the header, size and checksum checks) and with its header's payload size and its
// checksum made to fit (the payload parser and the id checks behind them).
//
// The seed corpus (corpus/map_file/) is written by this binary: BESLAM_FUZZ_WRITE_SEEDS=DIR map_file
// saves a two-keyframe map built with the backend's test helpers (test/map_builder.hpp) and exits.
#include "map_io/map_file.hpp"

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "features/checksum.hpp"
#include "features/scale_pyramid.hpp"
#include "fuzz_support.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "map_builder.hpp"

namespace {

namespace orb = beslam::orb;

constexpr size_t kHeaderBytes = 8 + 4 + 8, kTrailerBytes = 8;

orb::MapFileInfo expectedInfo() {
  orb::MapFileInfo info;
  info.camera = orb::Camera{160, 120, 100, 100, 80, 60};
  info.levels = 3;
  info.scale_factor = 1.2;
  return info;
}

const orb::ScalePyramid& pyramid() {
  static const orb::ScalePyramid p(3, 1.2);
  return p;
}

void writeSeeds(const std::string& dir) {
  const orb::MapFileInfo info = expectedInfo();
  std::vector<Eigen::Isometry3d> poses(2, Eigen::Isometry3d::Identity());
  poses[1].translation() = Eigen::Vector3d(-0.5, 0, 0);
  const std::vector<Eigen::Vector3d> points = {{-1, -0.5, 5},  {0, -0.4, 6},    {1, 0.3, 5.5},
                                               {-0.6, 0.5, 7}, {0.4, 0.1, 4.5}, {0.8, -0.7, 6.5}};
  orb::Map map;
  const auto kfs = orb::test::buildMap(map, info.camera, pyramid(), poses, poses, points, points, 0, 1);
  map.setOrigin(kfs[0]);
  orb::ObjectLandmark car;
  car.id = 3;
  car.confidence = 0.8;
  car.T_world_object.translation() = Eigen::Vector3d(2, 1, 9);
  car.dimensions = Eigen::Vector3d(4.2, 1.8, 1.5);
  car.points_object = {{2, 0.9, 0}, {-2, 0.9, 0.2}};
  std::filesystem::create_directories(dir);
  orb::saveMapFile(dir + "/two-keyframes.map", map, info, {car});
  orb::saveMapFile(dir + "/no-objects.map", map, info, {});
}

// Loads `path`; a loader error must name the file.
bool load(const std::string& path, orb::Map& map, std::vector<orb::ObjectLandmark>& landmarks) {
  try {
    orb::loadMapFile(path, expectedInfo(), pyramid(), map, landmarks);
    return true;
  } catch (const std::runtime_error& e) {
    beslam::fuzz::require(std::strncmp(e.what(), ("map file '" + path + "': ").c_str(), path.size() + 13) == 0,
                          "a map file error that does not name the file");
    beslam::fuzz::require(map.numKeyFrames() == 0 && map.points().empty(), "a refused map file changed the map");
    return false;
  }
}

void loadAndRoundTrip(const std::string& path) {
  orb::Map map;
  std::vector<orb::ObjectLandmark> landmarks;
  if (!load(path, map, landmarks)) return;
  const std::string again = path + ".again";
  orb::saveMapFile(again, map, expectedInfo(), landmarks);
  orb::Map reloaded;
  std::vector<orb::ObjectLandmark> reloaded_landmarks;
  beslam::fuzz::require(load(again, reloaded, reloaded_landmarks), "a map that loaded does not load once saved");
  beslam::fuzz::require(reloaded.numKeyFrames() == map.numKeyFrames() &&
                            reloaded.points().size() == map.points().size() &&
                            reloaded_landmarks.size() == landmarks.size(),
                        "a saved and reloaded map has other counts");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) { return beslam::fuzz::writeSeedsIfAsked(writeSeeds); }

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  loadAndRoundTrip(beslam::fuzz::writeScratch(data, size, "map.bin"));
  if (size >= kHeaderBytes + kTrailerBytes && std::memcmp(data, "BESLAMAP", 8) == 0) {
    std::string bytes(reinterpret_cast<const char*>(data), size);
    const uint64_t payload = size - kHeaderBytes - kTrailerBytes;
    const uint64_t sum = orb::fnv1a(bytes.data() + kHeaderBytes, payload);
    beslam::fuzz::putLittleEndian64(bytes, 12, payload);
    beslam::fuzz::putLittleEndian64(bytes, size - 8, sum);
    loadAndRoundTrip(
        beslam::fuzz::writeScratch(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), "map-fitted.bin"));
  }
  return 0;
}
