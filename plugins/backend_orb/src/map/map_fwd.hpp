// Forward declarations of the map's classes (the frame being tracked, keyframes, map points, the map, its
// gate and the keyframe database), for headers that hold only pointers or references to them.
#pragma once

namespace beslam::orb {

struct Frame;
class KeyFrame;
class KeyFrameDatabase;
class Map;
class MapGate;
class MapPoint;

}  // namespace beslam::orb
