// detector_lidar: the SDK wrapper around beslam::detector_lidar::LidarDetector (PCL BEV car detector).
#include <string>

#include "beslam/detector_lidar/lidar_detector.hpp"
#include "beslam/sdk/sdk.hpp"

namespace {

using beslam::detector_lidar::Options;
using beslam::sdk::setting;

// Each setting once: its schema entry and the Options member it sets.
// clang-format off: one setting a line
const beslam::sdk::Settings<Options> kSettings{
    setting(&Options::min_range, "min_range", "1.5", 0, 200, "points closer to the LiDAR than this (m) are ignored"),
    setting(&Options::max_range, "max_range", "60", 1, 300, "points farther than this (m) are ignored"),
    setting(&Options::camera_fov_only, "camera_fov_only", "true",
            "report only cars with points that project into the image"),
    setting(&Options::fov_margin_px, "fov_margin_px", "40", 0, 10000,
            "image grown by this many pixels for camera_fov_only"),
    setting(&Options::ground_method, "ground_method", "ransac", "ransac|grid",
            "ground removal: one RANSAC plane, or a BEV grid of local lowest points"),
    setting(&Options::ground_threshold, "ground_threshold", "0.25", 0.01, 2,
            "points up to this height above the ground (m) are ground"),
    setting(&Options::max_ground_tilt_deg, "max_ground_tilt_deg", "10", 0.1, 44,
            "ransac: largest angle between ground normal and camera y"),
    setting(&Options::ransac_iterations, "ransac_iterations", "200", 1, 100000, "ransac: iterations"),
    setting(&Options::grid_cell, "grid_cell", "0.5", 0.05, 10, "grid: cell size (m)"),
    setting(&Options::grid_radius, "grid_radius", "6", 0, 50,
            "grid: local ground is the lowest point within this many cells"),
    setting(&Options::max_height, "max_height", "3.0", 0.1, 20,
            "points higher than this above the ground (m) are ignored"),
    setting(&Options::voxel_size, "voxel_size", "0.12", 0, 1,
            "voxel grid (m) the cloud is thinned to before clustering; 0: none"),
    setting(&Options::cluster_tolerance, "cluster_tolerance", "0.5", 0.05, 5, "Euclidean clustering distance (m)"),
    setting(&Options::min_cluster_points, "min_cluster_points", "8", 3, 1000000, "smallest cluster kept"),
    setting(&Options::max_cluster_points, "max_cluster_points", "25000", 3, 10000000, "largest cluster kept"),
    setting(&Options::box_fit, "box_fit", "lshape", "lshape|min_area",
            "BEV rectangle: L-shape search or minimum-area rectangle"),
    setting(&Options::angle_step_deg, "angle_step_deg", "1", 0.05, 45, "lshape: heading search step (degrees)"),
    setting(&Options::lshape_min_points, "lshape_min_points", "40", 0, 1000000,
            "lshape: clusters with fewer points (after thinning) get the minimum-area rectangle"),
    setting(&Options::car_min_extent, "car_min_extent", "1.0", 0.01, 20,
            "car gate: the longer footprint side reaches at least this (m)"),
    setting(&Options::car_max_length, "car_max_length", "6.5", 0.1, 50, "car gate: longest footprint side (m)"),
    setting(&Options::car_max_width, "car_max_width", "2.8", 0.1, 50, "car gate: shorter footprint side at most (m)"),
    setting(&Options::car_min_top, "car_min_top", "0.9", 0, 20,
            "car gate: the cluster's top is at least this high (m)"),
    setting(&Options::car_max_top, "car_max_top", "2.0", 0.1, 20,
            "car gate: the cluster's top is at most this high (m)"),
    setting(&Options::car_max_bottom, "car_max_bottom", "1.6", 0, 20,
            "car gate: the cluster's lowest point is at most this high (m)"),
    setting(&Options::car_size, "car_size", "[3.9, 1.6, 1.5]", 0.1, 20,
            "car prior length, width, height (m): unseen sides are grown to it"),
    setting(&Options::car_min_length, "car_min_length", "2.2", 0.1, 20,
            "without free_space: a seen side shorter than this (m) is grown to the prior length"),
    setting(&Options::car_min_width, "car_min_width", "1.2", 0.1, 20,
            "without free_space: a seen end narrower than this (m) is grown to the prior width"),
    setting(&Options::fov_context, "fov_context", "5.0", 0, 50,
            "points up to this far (m) outside the image's view still shape boxes"),
    setting(&Options::free_space, "free_space", "true",
            "grow boxes only where no LiDAR ray passed through at body height"),
    setting(&Options::free_space_min_height, "free_space_min_height", "0.4", 0, 5,
            "free space: lowest body height above the ground (m)"),
    setting(&Options::free_space_max_height, "free_space_max_height", "0.9", 0.01, 5,
            "free space: highest body height above the ground (m)"),
    setting(&Options::free_space_min_rays, "free_space_min_rays", "3", 1, 1000,
            "free space: rays needed to call a place free"),
    setting(&Options::uncertain_range, "uncertain_range", "40", 0.1, 1000,
            "boxes farther than this (m) are flagged uncertain"),
    setting(&Options::uncertain_points, "uncertain_points", "25", 0, 1000000,
            "boxes with fewer points are flagged uncertain"),
};
// clang-format on

const beslam::sdk::PluginInfo kInfo(
    "detector_lidar", "LiDAR BEV car detector",
    "Cars from one LiDAR scan: ground removal, Euclidean clustering, L-shape BEV boxes (PCL)", {1, 0, 0}, kSettings);

Options readOptions(const beslam::sdk::Config& config) {
  const Options o = kSettings.read(config);
  try {
    o.validate();
  } catch (const std::invalid_argument& e) {
    throw beslam::sdk::ConfigError(e.what());
  }
  return o;
}

beslam::detector_lidar::LidarDetector makeDetector(const beslam::sdk::Context& context,
                                                   const beslam::sdk::Config& config) {
  if (!context.T_cam_lidar())
    throw beslam::sdk::ConfigError(
        "detector_lidar needs the LiDAR-to-camera extrinsics (T_cam_lidar), and the dataset gave none: use a "
        "dataset with a LiDAR calibration (KITTI Tr_velo_to_cam) and `lidar: true`");
  std::optional<beslam_camera> camera;
  if (context.camera().width > 0 && context.camera().height > 0) camera = context.camera();
  return beslam::detector_lidar::LidarDetector(readOptions(config), *context.T_cam_lidar(), camera);
}

class DetectorLidar : public beslam::sdk::Detector {
 public:
  DetectorLidar(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : context_(context), detector_(makeDetector(context, config)) {}

  std::vector<beslam_box3d> detect(const beslam::sdk::Frame& frame) override {
    if (!frame.hasLidar()) {
      if (!warned_no_scan_)
        context_.warn("frame " + std::to_string(frame.index) +
                      " has no LiDAR scan (is `lidar: true` set in the dataset?): no boxes until one arrives");
      warned_no_scan_ = true;
      return {};
    }
    if (frame.lidar.stride_bytes != 0 && (frame.lidar.stride_bytes < 16 || frame.lidar.stride_bytes % 4 != 0))
      throw std::invalid_argument("LiDAR scan with stride " + std::to_string(frame.lidar.stride_bytes) +
                                  " bytes (need a multiple of 4, at least 16)");
    const std::size_t stride = frame.lidar.stride_bytes == 0 ? 4 : frame.lidar.stride_bytes / 4;
    beslam::detector_lidar::Stats stats;
    std::vector<beslam_box3d> boxes = detector_.detect(frame.lidar.data, frame.lidar.count, stride, &stats);
    if (stats.invalid_points > 0 && !warned_invalid_)
      context_.warn("frame " + std::to_string(frame.index) + ": " + std::to_string(stats.invalid_points) +
                    " LiDAR points with NaN/inf coordinates were skipped (reported once)");
    warned_invalid_ = warned_invalid_ || stats.invalid_points > 0;
    return boxes;
  }

 private:
  const beslam::sdk::Context& context_;
  beslam::detector_lidar::LidarDetector detector_;
  bool warned_no_scan_ = false, warned_invalid_ = false;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<DetectorLidar>(kInfo))
