// beslam::sim — the project's embedded default data: deterministic, procedurally built street scenes
// rendered with full ground truth (`beslam synth`).
//
// Contract
// - A SynthConfig (YAML, presets in configs/synth/) fully determines the output: same config and seed,
//   same bytes on every run, whatever the number of worker threads.
// - Output is laid out like KITTI so the same readers serve real and synthetic data (NN = config sequence):
//     OUT/poses/NN.txt                       T_world_cam0 per frame, 3x4 row-major (world = cam0 at frame 0)
//     OUT/sequences/NN/calib.txt             P0: P1: P2: P3: R0_rect: Tr_velo_to_cam: Tr:  (one camera:
//                                            P0 = P1 = P2 = P3, R0_rect = I, Tr = Tr_velo_to_cam)
//     OUT/sequences/NN/times.txt             seconds, one line per frame
//     OUT/sequences/NN/image_0/NNNNNN.png    grey 8-bit        (camera.grey)
//     OUT/sequences/NN/image_2/NNNNNN.png    colour 8-bit BGR  (camera.colour)
//     OUT/sequences/NN/velodyne/NNNNNN.bin   float32 x y z intensity, LiDAR frame (x fwd, y left, z up)
//     OUT/sequences/NN/instance/NNNNNN.png   16-bit, 0 = background, else the object's track id
//     OUT/sequences/NN/depth/NNNNNN.png      16-bit camera z * 256, 0 = sky (only with output.depth)
//     OUT/sequences/NN/label_02/NN.txt       KITTI tracking rows: frame track_id type truncated occluded
//                                            alpha x1 y1 x2 y2 h w l x y z ry (camera frame, y down,
//                                            location = bottom centre, ry about camera y)
//     OUT/sequences/NN/objects_motion.txt    frame track_id moving(0/1) speed(m/s), every object, every frame
//     OUT/sequences/NN/objects/objects.txt   track_id type behaviour l w h (one row per object)
//     OUT/sequences/NN/objects/poses.txt     frame track_id T_world_obj (12 numbers, 3x4 row-major)
//     OUT/sequences/NN/objects/car_TTTT.ply  every car's mesh in its object frame
//     OUT/sequences/NN/manifest.yaml         seed, every parameter, object counts, loop length
//   Object frame (meshes, T_world_obj): KITTI box convention, origin at the bottom centre of the box,
//   x forward, y down, z left, so T_cam_obj ~= [Ry(ry) | location] of the label.
// - Track ids start at 1 (0 is the mask background). Cars are "Car" or "Van", people "Pedestrian".
// - Errors in the config throw beslam::Error with one line naming the file and the key.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace beslam::sim {

struct SynthConfig {
  std::uint64_t seed = 7;
  std::string sequence = "00";
  int frames = 500;
  double rate_hz = 10.0;

  struct Camera {
    int width = 1241, height = 376;
    double fx = 718.856, fy = 718.856, cx = 607.1928, cy = 185.2157;
    double mount_height = 1.65;  // metres above the road
    bool grey = true;            // image_0
    bool colour = true;          // image_2
  } camera;

  struct Ego {
    double speed_kmh = 33.0;           // cruise speed on straights
    double max_lateral_accel = 3.0;    // m/s^2, slows the ego in turns
    bool clockwise = true;             // direction round the loop block
    double start_fraction = 0.0;       // where on the loop frame 0 is (0..1 of its length)
    double pitch_amplitude_deg = 0.3;  // small body motion
    double roll_per_accel_deg = 0.25;  // roll per m/s^2 of lateral acceleration
  } ego;

  struct World {
    std::string type = "urban";               // urban (street grid) or highway (wide fast ring road)
    int blocks_x = 3, blocks_y = 3;           // street grid; the ego loops round the centre block
    double block_x = 100.0, block_y = 110.0;  // street centreline spacing (m)
    int lanes_per_direction = 1;
    double lane_width = 3.25;
    bool parking_lanes = true;
    double pavement_width = 3.5;
    double corner_radius = 16.0;  // centreline corner radius of the routes (m)
    double building_min_height = 8.0, building_max_height = 22.0;
    double building_gap_probability = 0.15;
    double building_setback_max = 3.0;
    double tree_spacing = 7.0;  // mean distance between trees along a pavement (0: none)
  } world;

  struct Objects {
    int parked = 50;
    int driving = 2;
    int stop_and_go = 1;
    int pedestrians = 4;
    double driving_speed_kmh_min = 25.0, driving_speed_kmh_max = 45.0;
  } objects;

  struct Image {
    double noise_sigma = 2.0;          // grey levels
    double blur_sigma = 0.4;           // pixels (0: none)
    double exposure_variation = 0.04;  // relative gain change between frames
  } image;

  struct Lidar {
    bool enabled = true;
    int beams = 64;
    double fov_up_deg = 2.0, fov_down_deg = -24.8;
    double horizontal_resolution_deg = 0.2;
    double max_range = 120.0;
    double range_noise = 0.005;  // metres, sigma
    double mount_height = 1.73;  // metres above the road
  } lidar;

  struct Output {
    bool depth = false;  // also write depth/NNNNNN.png
    int threads = 2;     // frame workers (output is identical for any value)
  } output;
};

// Parses and validates a config tree. `source` names it in errors ("configs/synth/x.yaml").
// Every key is optional (defaults above); unknown keys, wrong types and out-of-range values throw
// beslam::Error "source: key 'a.b': cause".
SynthConfig synthConfigFromYaml(const YAML::Node& root, const std::string& source);
// Reads a file, applies `--set k=v` overrides, then validates as above.
SynthConfig loadSynthConfig(const std::string& path, const std::vector<std::string>& set_overrides = {});
// The full config as YAML (what the manifest records).
std::string synthConfigToYaml(const SynthConfig& config);
// Built-in presets: "urban_loop" (the default), "static_loop", "static_street", "dynamic_street",
// "highway". Same values as configs/synth/<name>.yaml. Throws beslam::Error on an unknown name.
SynthConfig presetConfig(const std::string& name);
std::vector<std::string> presetNames();

enum class Behaviour { Parked, Driving, StopAndGo, Pedestrian };
const char* behaviourName(Behaviour b);

struct ObjectInfo {
  int track_id = 0;
  std::string type;   // Car, Van, Pedestrian
  std::string shape;  // sedan, hatchback, suv, van, wagon, pedestrian
  Behaviour behaviour = Behaviour::Parked;
  double length = 0, width = 0, height = 0;
};

struct ObjectState {
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();  // KITTI world, KITTI object frame
  double speed = 0;                                               // m/s
  bool moving = false;
};

// One label row (KITTI tracking format) in the camera frame.
struct ObjectLabel {
  int track_id = 0;
  std::string type;
  double truncated = 0;  // 0..1
  int occluded = 0;      // 0 visible, 1 partly, 2 largely occluded
  double alpha = 0;
  double x1 = 0, y1 = 0, x2 = 0, y2 = 0;  // full projected extent, clipped to the image
  double h = 0, w = 0, l = 0;
  Eigen::Vector3d location = Eigen::Vector3d::Zero();  // bottom centre, camera frame
  double ry = 0;
  int visible_pixels = 0;
};

struct FrameRender {
  int index = 0;
  double stamp = 0;
  cv::Mat grey;              // CV_8UC1
  cv::Mat colour;            // CV_8UC3, BGR
  cv::Mat instance;          // CV_16UC1
  cv::Mat depth;             // CV_32FC1, camera z in metres, 0 where sky
  std::vector<float> lidar;  // x y z intensity, LiDAR frame
  std::vector<ObjectLabel> labels;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // KITTI world (cam0 at frame 0)
};

struct SequenceSummary {
  int frames = 0;
  int parked = 0, driving = 0, stop_and_go = 0, pedestrians = 0;  // objects actually placed
  double loop_length_m = 0;                                       // the ego's loop
  double distance_m = 0;                                          // driven over the sequence
  double laps = 0;
};

class World;  // the built scene (geometry, materials, trajectories); opaque

// Builds the world once; renders any frame independently and thread-safely (render() is const).
class Synthesizer {
 public:
  explicit Synthesizer(const SynthConfig& config);
  ~Synthesizer();
  Synthesizer(const Synthesizer&) = delete;
  Synthesizer& operator=(const Synthesizer&) = delete;

  const SynthConfig& config() const;
  int frameCount() const;
  FrameRender render(int frame) const;
  // The same, reusing out's buffers (no fresh multi-megabyte allocations per frame).
  void render(int frame, FrameRender& out) const;

  Eigen::Matrix<double, 3, 4> projection() const;  // P0 (= P2)
  Eigen::Isometry3d T_cam_velo() const;            // Tr_velo_to_cam
  Eigen::Isometry3d T_world_cam(int frame) const;  // ground truth, KITTI world
  const std::vector<ObjectInfo>& objects() const;
  ObjectState objectState(int track_id, int frame) const;
  // A car's mesh in its object frame (empty for pedestrians, whose mesh is animated).
  void objectMesh(int track_id, std::vector<Eigen::Vector3f>& vertices, std::vector<std::array<int, 3>>& faces) const;
  SequenceSummary summary() const;

 private:
  std::unique_ptr<World> world_;
  std::vector<ObjectInfo> infos_;
};

// Renders the whole sequence into out_dir (layout above) with config.output.threads workers.
// `progress`, when non-null, receives a carriage-return progress line.
SequenceSummary generateSequence(const SynthConfig& config, const std::string& out_dir,
                                 std::ostream* progress = nullptr);

// Writes small illustration images of one frame into dir: synth_frame.jpg (colour), synth_mask.png
// (instance ids in false colour over the grey image), synth_lidar_bev.png (bird's-eye view of the scan).
void writePreview(const SynthConfig& config, int frame, const std::string& dir);

// The default demo sequence (preset `name`, urban_loop by default), generated into
// cache_dir/<name>-<config hash>/ unless a complete copy is already there. Returns that directory,
// a KITTI odometry root (sequences/00, poses/00.txt).
std::string ensureDefaultSequence(const std::string& cache_dir, const std::string& name = "urban_loop",
                                  std::ostream* progress = nullptr);
// The same for any config: cache_dir/<name>-<hash of the full config>/, rendered once.
std::string ensureSequence(const std::string& cache_dir, const SynthConfig& config, const std::string& name,
                           std::ostream* progress = nullptr);

// `beslam synth` (args exclude the program name and "synth"):
//   --config FILE (or a preset name), --out DIR, --set k=v (repeatable), --preview DIR, --frame N, --help.
// Returns 0 ok, 2 usage error, 1 input error (one line on err naming the file and the cause).
int runSynthCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace beslam::sim
