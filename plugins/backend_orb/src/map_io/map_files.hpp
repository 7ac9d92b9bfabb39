// MapFiles: the facade's map files (OrbSlam::saveMap / loadMap, MapReuseOptions). What a map file made by
// this run records besides the map (the camera, the pyramid, whether the map is in metres; map_file.hpp),
// and saving or loading the map with its object landmarks. Poses are saved as the map holds them (T_cw,
// world to camera); a metric map's world is in metres.
#pragma once

#include <string>

#include "beslam_orb/options.hpp"
#include "features/scale_pyramid.hpp"
#include "map_io/map_file.hpp"

namespace beslam::orb {

class Map;

class MapFiles {
 public:
  MapFiles(const Camera& camera, const ExtractorOptions& extractor) : camera_(camera), extractor_(extractor) {}

  // What a map file of this run records; the vocabulary identity stays empty until there is a
  // place-recognition vocabulary.
  MapFileInfo info(bool metric) const;
  // The live keyframes, map points and object landmarks of `map` to `path` (atomically).
  void save(const std::string& path, const Map& map, bool metric) const;
  // Reads `path` into the empty `map` (its object landmarks into map.objects()); keyframes use `pyramid`.
  // Returns the file's info. Throws std::runtime_error naming the file and the problem.
  MapFileInfo load(const std::string& path, const ScalePyramid& pyramid, Map& map) const;

 private:
  Camera camera_;
  ExtractorOptions extractor_;
};

}  // namespace beslam::orb
