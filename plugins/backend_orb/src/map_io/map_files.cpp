#include "map_io/map_files.hpp"

#include <vector>

#include "beslam_orb/types.hpp"
#include "map/map.hpp"

namespace beslam::orb {

MapFileInfo MapFiles::info(bool metric) const {
  MapFileInfo info;
  info.camera = camera_;
  info.levels = extractor_.levels;
  info.scale_factor = extractor_.scale_factor;
  info.metric = metric;
  return info;
}

void MapFiles::save(const std::string& path, const Map& map, bool metric) const {
  saveMapFile(path, map, info(metric), map.objects().landmarks());
}

MapFileInfo MapFiles::load(const std::string& path, const ScalePyramid& pyramid, Map& map) const {
  std::vector<ObjectLandmark> loaded;
  // The expected info's metric flag is not checked: the file says whether its map is in metres.
  const MapFileInfo file = loadMapFile(path, info(false), pyramid, map, loaded);
  for (const ObjectLandmark& l : loaded) map.objects().add(l, map.lastKeyFrameId());
  return file;
}

}  // namespace beslam::orb
