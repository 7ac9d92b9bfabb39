// beslam::orb::OrbSlam: an ORB-SLAM2-class monocular SLAM core (tracking, local mapping, relocalisation and
// loop closing), the plugin's facade. Its options are in beslam_orb/options.hpp (one struct per module),
// the data it takes and returns per frame in beslam_orb/types.hpp.
//
// One call per frame: track(grey image, optional label mask, timestamp, frame index). Poses are
// T_world_cam (camera-to-world). The world is the first keyframe's camera frame, scaled so the median
// scene depth at initialisation is 1.
//
// Label mask (CV_16UC1, same size as the image, or empty): 0 = background, 1 = dynamic object (no
// features), >= 1000 = static object 1000 + id (lower FAST threshold, a reserved share of the budget,
// map points made there are "trusted": never culled as recent points, weighted by
// Options::static_object_weight in pose optimisation and bundle adjustment; 1.0 by default).
//
// Map reuse: loadMap() / saveMap() (or Options::map_reuse: load_map / save_map) and
// MapReuseOptions::localisation_only.
//
// Threading (Options::threading): with threaded_mapping the local mapping of a new keyframe runs on its own
// thread (mapping/mapping_thread.hpp) while the caller goes on (and while the next frame's features are
// extracted); tracking of the next frame waits for it. Results are the same as in the default
// single-threaded mode. With concurrent_mapping tracking does not wait for a keyframe's mapping (ORB-SLAM2's
// model): faster, but results depend on thread timing.
// With a mapping thread, addObjectLandmarks() and dropObject() return at once: their changes are applied in
// call order once mapping is idle (before the next frame is tracked, or by any accessor), the same order
// against mapping as inline, so they change no result.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "beslam_orb/options.hpp"
#include "beslam_orb/types.hpp"

namespace beslam::orb {

struct FramePose {
  int64_t frame_index = 0;
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
};

// A map point as exported (PLY output): position, colour, observation count.
struct CloudPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  uint8_t grey = 0;
  uint8_t r = 0, g = 0, b = 0;
  int observations = 0;
  bool on_static_object = false;
};

struct Statistics {
  int frames = 0, frames_tracked = 0, keyframes = 0, keyframes_culled = 0, map_points = 0;
  int resets = 0, relocalisations = 0;
  int loop_closures = 0, loop_object_rejections = 0, loop_candidates = 0;
  int relocalisation_object_rejections = 0;
  std::vector<std::pair<int64_t, int64_t>> loop_frames;  // (frame, matched earlier frame) per closure
  int64_t initialised_at_frame = -1;
  int64_t metric_from_frame = -1;   // first frame tracked in metres (-1: never)
  double metric_scale_factor = 0;   // the factor the map was multiplied by then
  int object_points_dropped = 0;    // map points of static objects that started to move
  int scale_corrections = 0;        // local scale corrections from the ground fits
  int64_t object_scale_frame = -1;  // frame at which the parked cars' boxes set the scale (-1: never)
  double object_scale_factor = 0;   // the factor they applied
  int object_scale_tracks = 0;      // cars in the agreeing cluster
  bool lidar_scaled = false;        // the LiDAR ranges set the scale (metric_from_frame) and hold it
  int lidar_points = 0;             // map points made from keyframes' LiDAR ranges (ScaleOptions::lidar_points)
};

class OrbSlam {
 public:
  // Throws std::invalid_argument on bad input, std::runtime_error when Options::map_reuse.load_map cannot be loaded.
  OrbSlam(const Camera& camera, const Options& options);
  ~OrbSlam();
  OrbSlam(const OrbSlam&) = delete;
  OrbSlam& operator=(const OrbSlam&) = delete;

  // Constant-velocity prediction of the next frame's pose (empty until tracking has a velocity). The
  // velocity is per frame (frames assumed evenly spaced); the timestamp is not used.
  std::optional<Eigen::Isometry3d> predictPose(double timestamp) const;

  // A frame's mask-independent extraction work (grey image, pyramids, FAST corners), done ahead of its
  // track() with the same image: safe to call from another thread while the other calls run. track()
  // returns the same with or without it.
  void prepare(const cv::Mat& gray, int64_t frame_index);

  // gray: CV_8UC1 (or CV_8UC3 BGR, converted; colour kept for map points); label_mask: CV_16UC1 or empty;
  // car_boxes: the frame's cars (ObjectBox; object_id -1 for untracked ones, which only relocalisation's
  // parked-car check uses), used with metric_scale. lidar_cam: the frame's LiDAR
  // scan in the camera frame (metres), if it has one; used with metric_scale and lidar_scale.
  TrackResult track(const cv::Mat& gray, const cv::Mat& label_mask, double timestamp, int64_t frame_index,
                    const std::vector<ObjectBox>& car_boxes = {}, const Eigen::Matrix3Xf* lidar_cam = nullptr);

  // Waits for the mapping thread and runs a last local bundle adjustment (not in localisation-only mode),
  // then saves the map to Options::map_reuse.save_map if set (throws std::runtime_error naming the file on failure).
  void finish();

  // Saves the map (live keyframes, map points, covisibility, object landmarks, camera) to `path`
  // atomically; throws std::runtime_error naming the file. Waits for the mapping thread.
  void saveMap(const std::string& path) const;
  // Loads a map file into this OrbSlam before its first track(); throws std::runtime_error naming the
  // file and the problem (another format version or camera, truncated, corrupt) and keeps no part of it.
  void loadMap(const std::string& path);

  // Each tracked frame: its pose relative to its reference keyframe composed with that keyframe's
  // current (optimised) pose. Untracked frames are absent.
  std::vector<FramePose> trajectory() const;
  // Each tracked frame's pose as tracking estimated it at the time.
  std::vector<FramePose> onlineTrajectory() const;
  std::vector<FramePose> keyframes() const;
  std::vector<CloudPoint> mapPoints() const;

  // Landmarks from a reconstructor: kept (same id replaces) and returned by objectLandmarks() (their poses as
  // local BA refined them). With Options::object_landmarks.mode = BA they enter local BA (docs/object-ba.md);
  // off, they are only stored. Trust comes from the mask: features on label 1000 + id.
  void addObjectLandmarks(const std::vector<ObjectLandmark>& landmarks);
  std::vector<ObjectLandmark> objectLandmarks() const;

  // Object `object_id` (mask label 1000 + id) started to move: its map points and its landmark leave the map.
  void dropObject(int32_t object_id);

  Statistics statistics() const;
  const Options& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace beslam::orb
