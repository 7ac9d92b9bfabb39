// Map files: a saved map (keyframes with poses, keypoints and descriptors; map points with positions,
// descriptors and observations; covisibility, spanning tree and loop edges; object landmarks), the camera
// and pyramid it was made with and the identity of the place-recognition vocabulary ("" while there is
// none).
//
// Layout (little-endian): 8-byte magic "BESLAMAP", u32 format version, u64 payload size, the payload,
// u64 FNV-1a checksum of the payload. Saving is atomic: a temporary file next to the target, flushed to
// disk, then renamed over it, so a failed save leaves an existing file as it was. Loading refuses, with
// one std::runtime_error "map file '<path>': <problem>" and the map untouched, a file that is not a map
// file, of another format version, truncated, corrupt (checksum, counts out of bounds, ids that do not
// resolve), made with another camera (size or intrinsics) or pyramid, or with another vocabulary (checked
// when both identities are non-empty).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "beslam_orb/options.hpp"
#include "beslam_orb/types.hpp"
#include "features/scale_pyramid.hpp"

namespace beslam::orb {

class Map;

// 2: object landmarks carry their confidence (version 1 files still load, with confidence 1).
// 3: keyframes carry their loop edges (older files load without).
constexpr uint32_t kMapFileVersion = 3;

// What a map file records besides the map, and what loading checks it against.
struct MapFileInfo {
  Camera camera;
  int levels = 0;  // image pyramid of the keypoints' octaves
  double scale_factor = 0;
  std::string vocabulary;  // identity of the vocabulary the map was made with; "" = none
  bool metric = false;     // the map is in metres
};

// Writes the live keyframes and map points of `map` and `landmarks` to `path` (atomically).
void saveMapFile(const std::string& path, const Map& map, const MapFileInfo& info,
                 const std::vector<ObjectLandmark>& landmarks);

// Reads `path` into `map`, which must be empty; keyframes use `pyramid` (the one `expected` describes).
// Returns the file's info; fills `landmarks`. Throws std::runtime_error naming the file and the problem.
MapFileInfo loadMapFile(const std::string& path, const MapFileInfo& expected, const ScalePyramid& pyramid, Map& map,
                        std::vector<ObjectLandmark>& landmarks);

}  // namespace beslam::orb
