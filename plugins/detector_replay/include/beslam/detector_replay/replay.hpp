// Published 3D detection results as ABI boxes (camera frame, geometric centre, size = l w h, yaw = KITTI
// rotation_y). The parsing core of the detector_replay plugin, also used by the motion benchmark.
//
// Formats:
//  - ab3dmot:        "frame,class_id,x1,y1,x2,y2,score,h,w,l,x,y,z,ry,alpha" rows (commas or spaces), one file
//                    per class and sequence (det_pointrcnn/<Class>/<SSSS>.txt); class ids 1 Pedestrian, 2 Car,
//                    3 Cyclist; (x, y, z) the bottom centre in rectified camera 2.
//  - kitti_tracking: a label_02/<SSSS>.txt file (frame track_id type ... ry [score]).
//  - kitti_object:   a label_2 folder with one <NNNNNN>.txt per frame (type ... ry [score]).
//  - nuscenes:       a nuScenes detection results JSON ({"results": {token: [box, ...]}}), BEVFormer's
//                    and Fast-BEV's output, moved from the global frame into the camera with the per-frame
//                    ego pose and the camera extrinsic (see NuScenesFrames and nuscenes.hpp).
// Problems (malformed rows, non-numbers and NaN, non-positive sizes, unknown classes, missing frames) are
// reported as "file:line: cause". With Policy::stop the first one throws std::runtime_error; with
// Policy::skip the row is left out and counted in the Report.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "beslam/data.h"
#include "beslam/formats/geometry.hpp"

namespace beslam::detector_replay {

enum class Policy { stop, skip };

struct Report {
  int64_t rows = 0;                   // data rows read (comments and blank lines excluded)
  int64_t boxes = 0;                  // boxes kept
  int64_t skipped = 0;                // malformed rows left out (Policy::skip)
  int64_t filtered = 0;               // well-formed rows removed by class / score / depth filters or DontCare
  std::vector<std::string> problems;  // the first few "file:line: cause" messages of skipped rows
  void problem(const std::string& message);
};

// Which boxes to keep, applied to every format.
struct Filter {
  std::vector<int32_t> classes;  // BESLAM_CLASS_* to keep; empty: all
  double min_score = -1e300;     // after the score transform
  double min_depth = -1e300;     // camera z of the centre
  double max_distance = 1e300;   // |centre| in the camera frame
  bool keeps(const beslam_box3d& box) const;
};

// Boxes per frame index (dense; frames without boxes are empty).
class DetectionTable {
 public:
  void add(int64_t frame, const beslam_box3d& box);
  void cover(int64_t frame);  // marks a frame as covered by the source even without boxes
  const std::vector<beslam_box3d>& at(int64_t frame) const;                       // empty for frames without boxes
  int64_t lastFrame() const { return static_cast<int64_t>(frames_.size()) - 1; }  // -1 when empty
  int64_t boxCount() const;
  size_t frameCount() const { return frames_.size(); }

 private:
  std::vector<std::vector<beslam_box3d>> frames_;
};

// Class names and ids. Returns false for a name the format does not know (an "unknown class").
// KITTI names and the KITTI label box geometry come from the SDK's formats (beslam/formats/geometry.hpp).
using formats::kittiClass;
// AB3DMOT ids: 1 Pedestrian, 2 Car, 3 Cyclist.
bool ab3dmotClass(int64_t id, int32_t& class_id);
// nuScenes detection names: car; truck bus trailer construction_vehicle (-> TRUCK); pedestrian;
// bicycle motorcycle (-> CYCLIST); barrier traffic_cone (-> UNKNOWN).
bool nuscenesClass(const std::string& name, int32_t& class_id);
// "Car,Van,Pedestrian" (ABI class names, case-insensitive; "all" or empty: every class) -> ids.
std::vector<int32_t> parseClassList(const std::string& list);

enum class ScoreTransform { none, sigmoid };

using formats::boxFromKitti;

// One AB3DMOT row; throws std::runtime_error "path:line: cause" when malformed. `frame` gets the frame.
beslam_box3d parseAb3dmotRow(const std::string& line, const std::string& path, int line_no, ScoreTransform transform,
                             int64_t& frame);

// Whole files into `table`. Frames with rows are covered; `report` accumulates counts.
void readAb3dmotFile(const std::string& path, const Filter& filter, Policy policy, ScoreTransform transform,
                     DetectionTable& table, Report& report);
void readKittiTrackingFile(const std::string& path, const Filter& filter, Policy policy, ScoreTransform transform,
                           DetectionTable& table, Report& report);
// One KITTI object label file (frame `frame`).
void readKittiObjectFile(const std::string& path, int64_t frame, const Filter& filter, Policy policy,
                         ScoreTransform transform, DetectionTable& table, Report& report);

// Calls each(line, line_no) for every line of the text file `path` (numbered from 1, a trailing '\r'
// removed); throws std::runtime_error "path: cannot open <what>" when it cannot be opened.
void forEachLine(const std::string& path, const std::string& what,
                 const std::function<void(const std::string& line, int line_no)>& each);

}  // namespace beslam::detector_replay
