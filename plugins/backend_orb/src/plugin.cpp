// backend_orb as a BE-SLAM backend plugin: OrbSlam behind the SDK's Backend base class.
#include <algorithm>
#include <filesystem>
#include <set>
#include <system_error>

#include "backend_orb_settings.hpp"  // kSettings, from settings.json
#include "beslam/sdk/sdk.hpp"
#include "beslam_orb/orb_slam.hpp"

namespace {

using beslam::orb::Options;
using beslam::orb::OrbSlam;

const beslam::sdk::PluginInfo kInfo(
    "backend_orb", "ORB monocular SLAM",
    "ORB-SLAM2-class monocular tracking, local mapping, relocalisation and loop closing; dynamic mask labels "
    "get no features, static objects get more; optional metric scale from the camera height; map save and "
    "load, localisation-only tracking",
    {0, 4, 0}, kSettings);

// The vocabulary a run uses: the setting's file, none for "none", else the default one (installed, or
// the source tree's, see docs/place-recognition.md); without one the backend runs without bag of words.
std::string resolveVocabulary(const std::string& setting, const beslam::sdk::Context& context) {
  // "none" (the host resolves paths against the pipeline's folder, so it arrives as <folder>/none).
  if (std::filesystem::path(setting).filename() == "none") return "";
  if (!setting.empty()) return setting;
  for (const char* candidate : {BESLAM_ORB_VOCABULARY_INSTALLED, BESLAM_ORB_VOCABULARY_SOURCE}) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec)) return candidate;
  }
  context.warn(
      "no ORB vocabulary found (set backend.vocabulary): bag-of-words matching and BoW relocalisation are off");
  return "";
}

beslam::orb::Options readOptions(const beslam::sdk::Config& config, const beslam::sdk::Context& context) {
  beslam::orb::Options o = kSettings.read(config);
  o.vocabulary = resolveVocabulary(o.vocabulary, context);
  o.scale.camera_height = context.cameraHeight().value_or(0);  // the rig's, from the dataset: not a setting
  std::string error;
  if (!o.validate(&error)) throw beslam::sdk::ConfigError(error);
  if (o.map_reuse.localisation_only && o.map_reuse.load_map.empty())
    throw beslam::sdk::ConfigError("localisation_only needs a map to localise in (load_map)");
  // A map that cannot be saved should fail the run now, not after it.
  if (!o.map_reuse.save_map.empty()) {
    const std::filesystem::path folder = std::filesystem::absolute(o.map_reuse.save_map).parent_path();
    std::error_code ec;
    if (!std::filesystem::is_directory(folder, ec))
      throw beslam::sdk::ConfigError("save_map: folder '" + folder.string() + "' does not exist");
    if (std::filesystem::is_directory(o.map_reuse.save_map, ec))
      throw beslam::sdk::ConfigError("save_map: '" + o.map_reuse.save_map + "' is a folder");
  }
  return o;
}

beslam::orb::Camera readCamera(const beslam::sdk::Context& context) {
  const beslam_camera& c = context.camera();
  if (c.width <= 0 || c.height <= 0 || c.fx <= 0 || c.fy <= 0)
    throw beslam::sdk::ConfigError("backend_orb needs the camera intrinsics (width, height, fx, fy > 0)");
  return {c.width, c.height, c.fx, c.fy, c.cx, c.cy};
}

int32_t toState(beslam::orb::TrackingState s) {
  switch (s) {
    case beslam::orb::TrackingState::Ok:
      return BESLAM_TRACKING_OK;
    case beslam::orb::TrackingState::Lost:
      return BESLAM_TRACKING_LOST;
    default:
      return BESLAM_TRACKING_NOT_INITIALIZED;
  }
}

class OrbBackend : public beslam::sdk::Backend {
 public:
  OrbBackend(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : slam_(readCamera(context), readOptions(config, context)), T_cam_lidar_(context.T_cam_lidar()) {
    if (!slam_.options().map_reuse.load_map.empty()) {
      const beslam::orb::Statistics s = slam_.statistics();
      context.info("map '" + slam_.options().map_reuse.load_map + "' loaded: " + std::to_string(s.keyframes) +
                   " keyframes, " + std::to_string(s.map_points) + " map points" +
                   (slam_.options().map_reuse.localisation_only ? " (localisation only)" : ""));
    }
  }

  // Colour (when given) only colours the map points; features come from the grey image.
  static const cv::Mat& trackingImage(const beslam::sdk::Frame& frame) {
    return frame.color.empty() ? frame.gray : frame.color;
  }

  std::optional<Eigen::Isometry3d> predictPose(const beslam::sdk::Frame& frame) override {
    return slam_.predictPose(frame.timestamp);
  }

  // Pyramids and FAST corners of the frame ahead of its track() (host producer thread, ABI 1.4).
  void prepare(const beslam::sdk::Frame& frame) override {
    const cv::Mat& image = trackingImage(frame);
    if (!image.empty()) slam_.prepare(image, frame.index);
  }

  beslam::sdk::TrackResult track(const beslam::sdk::Frame& frame, const cv::Mat& mask,
                                 const std::vector<beslam_box3d>& boxes) override {
    // An object once parked (its points trusted) that the motion checker now calls moving: its points go.
    for (const beslam_box3d& b : boxes) {
      if (b.track_id < 0) continue;
      if (b.motion_state == BESLAM_MOTION_STATIC) {
        static_tracks_.insert(b.track_id);
      } else if (b.motion_state == BESLAM_MOTION_DYNAMIC && static_tracks_.erase(b.track_id)) {
        slam_.dropObject(b.track_id);
      }
    }
    const cv::Mat& image = trackingImage(frame);
    // Cars' metric boxes: tracked ones are the scale source before the map is metric (parked cars agree on
    // it), and for parked ones range priors in local BA after; every one (untracked: id -1, as after a
    // blackout) is where relocalisation's parked-car check looks for cars.
    std::vector<beslam::orb::ObjectBox> car_boxes;
    for (const beslam_box3d& b : boxes)
      if (b.class_id == BESLAM_CLASS_CAR || b.class_id == BESLAM_CLASS_VAN || b.class_id == BESLAM_CLASS_TRUCK)
        car_boxes.push_back({b.track_id >= 0 ? b.track_id : -1,
                             b.track_id >= 0 && b.motion_state == BESLAM_MOTION_STATIC, beslam::sdk::boxPose(b),
                             Eigen::Vector3d(b.size[0], b.size[2], b.size[1])});
    // The frame's LiDAR scan in the camera frame: a metric scale source (ScaleOptions::lidar_scale).
    std::optional<Eigen::Matrix3Xf> lidar_cam;
    if (frame.hasLidar() && T_cam_lidar_ && slam_.options().scale.metric_scale && slam_.options().scale.lidar_scale) {
      const Eigen::Isometry3f T = T_cam_lidar_->cast<float>();
      lidar_cam = (T.linear() * frame.lidarPoints().topRows<3>()).colwise() + T.translation();
    }
    const beslam::orb::TrackResult r =
        slam_.track(image, mask, frame.timestamp, frame.index, car_boxes, lidar_cam ? &*lidar_cam : nullptr);
    beslam::sdk::TrackResult out;
    out.state = toState(r.state);
    out.is_keyframe = r.is_keyframe;
    out.keyframe_id = r.keyframe_id;
    out.tracked_points = r.tracked_points;
    out.T_world_cam = r.T_world_cam;
    out.stage_ms = r.stage_ms;
    out.world_is_metric = r.world_is_metric;
    out.counters = {{"features", r.features},
                    {"features_static", r.features_static},
                    {"features_lidar", r.features_lidar},
                    {"lidar_points", r.lidar_points},
                    {"tracked_static", r.tracked_static},
                    {"relocalisations", r.relocalised ? 1 : 0},
                    {"loop_closures", r.loop_closed ? 1 : 0},
                    {"loop_correction_m", r.loop_correction_m},
                    {"loop_object_rejections", r.loop_object_rejections},
                    {"relocalisation_object_rejections", r.relocalisation_object_rejections},
                    {"object_landmarks", r.object_landmarks},
                    {"object_factors", r.object_factors}};
    out.S_new_old = r.S_new_old;
    out.world_change_scale = r.world_change_scale;
    out.keypoints.reserve(r.keypoints.size());
    for (const auto& k : r.keypoints)
      out.keypoints.push_back(
          {k.x, k.y, k.label, static_cast<uint8_t>(k.matched ? BESLAM_KEYPOINT_MATCHED : 0u), k.octave});
    out.keyframe_points.reserve(r.keyframe_points.size());
    for (const auto& p : r.keyframe_points)
      out.keyframe_points.push_back({p.id, p.p_world, Eigen::Vector2f(p.x, p.y), p.label, p.observations});
    return out;
  }

  void addLandmarks(const std::vector<beslam::sdk::Landmark>& landmarks) override {
    std::vector<beslam::orb::ObjectLandmark> mine;
    for (const beslam::sdk::Landmark& l : landmarks) {
      if (l.removed) {  // the reconstructor ended it (it started to move): its landmark and points go
        slam_.dropObject(l.track_id);
        continue;
      }
      beslam::orb::ObjectLandmark o;
      o.id = l.track_id;
      o.confidence = l.confidence;
      o.T_world_object = l.T_world_object;
      o.dimensions = l.scale;
      for (size_t i = 0; i + 2 < l.surface_points.size(); i += 3)
        o.points_object.emplace_back(l.surface_points[i], l.surface_points[i + 1], l.surface_points[i + 2]);
      mine.push_back(std::move(o));
    }
    slam_.addObjectLandmarks(mine);
  }

  void finish() override { slam_.finish(); }

  std::vector<beslam::sdk::TrajectoryEntry> trajectory(int32_t which) override {
    std::vector<beslam::orb::FramePose> poses;
    if (which == BESLAM_TRAJECTORY_ONLINE) {
      poses = slam_.onlineTrajectory();
    } else if (which == BESLAM_TRAJECTORY_KEYFRAMES) {
      poses = slam_.keyframes();
    } else if (which == BESLAM_TRAJECTORY_FINAL) {
      poses = slam_.trajectory();
    } else {
      throw std::invalid_argument("trajectory: unknown kind " + std::to_string(which));
    }
    std::vector<beslam::sdk::TrajectoryEntry> out;
    out.reserve(poses.size());
    for (const auto& p : poses) out.push_back({p.frame_index, p.timestamp, p.T_world_cam});
    return out;
  }

  std::vector<beslam_map_point> mapPoints() override {
    std::vector<beslam_map_point> out;
    for (const beslam::orb::CloudPoint& p : slam_.mapPoints()) {
      beslam_map_point m{};
      for (int i = 0; i < 3; ++i) m.p_world[i] = p.position[i];
      m.color[0] = p.r;
      m.color[1] = p.g;
      m.color[2] = p.b;
      m.observations = p.observations;
      m.flags = p.on_static_object ? BESLAM_MAP_POINT_STATIC_OBJECT : 0;
      out.push_back(m);
    }
    return out;
  }

 private:
  OrbSlam slam_;
  std::optional<Eigen::Isometry3d> T_cam_lidar_;  // the rig's LiDAR extrinsics, if it has a LiDAR
  std::set<int32_t> static_tracks_;               // track ids the motion checker has called static
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<OrbBackend>(kInfo))
