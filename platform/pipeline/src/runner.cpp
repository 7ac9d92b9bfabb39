#include "beslam/pipeline/runner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/datasets/dataset.hpp"
#include "beslam/eval/eval.hpp"
#include "beslam/pipeline/objects.hpp"
#include "beslam/registry/instance.hpp"
#include "beslam/sdk/views.hpp"  // the host uses the SDK's zero-copy view helpers too
#include "beslam/sim/synth.hpp"
#include "beslam/common/yaml_set.hpp"
#include "beslam/trajectory/trajectory.hpp"

namespace fs = std::filesystem;

namespace beslam::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Boxes from a detector must be finite and sized before any other plugin sees them.
void checkBoxes(const std::vector<beslam_box3d>& boxes, const registry::Plugin& detector,
                const datasets::Frame& frame) {
  for (size_t i = 0; i < boxes.size(); ++i) {
    const beslam_box3d& b = boxes[i];
    const char* bad = nullptr;
    for (double v : b.center_cam) bad = std::isfinite(v) ? bad : "a non-finite centre";
    for (double v : b.size) bad = bad ? bad : (std::isfinite(v) && v > 0 ? nullptr : "a non-finite or non-positive size");
    if (!bad && !std::isfinite(b.yaw)) bad = "a non-finite yaw";
    if (!bad && !std::isfinite(b.score)) bad = "a non-finite score";
    if (!bad && (b.flags & BESLAM_BOX_HAS_VELOCITY))
      for (double v : b.velocity_cam) bad = std::isfinite(v) ? bad : "a non-finite velocity";
    if (bad)
      throw Error("plugin " + detector.id + " (" + detector.library_path + "): frame " + std::to_string(frame.index) +
                  " (" + frame.image_path + "): box " + std::to_string(i) + " has " + bad);
  }
}

void writeTrajectory(const std::string& dir, const std::string& stem, const std::vector<registry::PoseEntry>& poses,
                     bool kitti_too) {
  trajectory::Trajectory t;
  for (const auto& p : poses) t.push_back(p.timestamp, p.T_world_cam);
  trajectory::writeTum((fs::path(dir) / (stem + ".tum")).string(), t);
  if (kitti_too) trajectory::writeKitti((fs::path(dir) / (stem + ".kitti")).string(), t);
}

void writePly(const std::string& path, const std::vector<beslam_map_point>& points) {
  writeFileAtomic(path, [&](std::ostream& out) {
    out << "ply\nformat ascii 1.0\ncomment BE-SLAM map points (world frame)\n"
        << "element vertex " << points.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n"
        << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        << "property int observations\nend_header\n";
    out << std::setprecision(7);
    for (const auto& p : points)
      out << p.p_world[0] << ' ' << p.p_world[1] << ' ' << p.p_world[2] << ' ' << int(p.color[0]) << ' '
          << int(p.color[1]) << ' ' << int(p.color[2]) << ' ' << p.observations << '\n';
  });
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct SynthSource {
  std::string name;
  sim::SynthConfig config;
};

// The synth config a `synth` dataset names: a preset (urban_loop, ...) or a YAML file, plus overrides.
SynthSource synthSource(const DatasetSpec& dataset) {
  std::vector<std::string> sets;
  std::stringstream ss(dataset.synth_set);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) sets.push_back(item);
  const std::string& seq = dataset.sequence.empty() ? std::string("urban_loop") : dataset.sequence;
  if (seq.size() > 5 && seq.substr(seq.size() - 5) == ".yaml")
    return {fs::path(seq).stem().string(), sim::loadSynthConfig(seq, sets)};
  if (sets.empty()) return {seq, sim::presetConfig(seq)};
  // A preset with overrides: through YAML so the overrides are validated like `beslam synth --set`.
  YAML::Node node = YAML::Load(sim::synthConfigToYaml(sim::presetConfig(seq)));
  for (const std::string& set : sets) applySetOverride(node, set);
  return {seq, sim::synthConfigFromYaml(node, "dataset.synth_set")};
}

struct TimingRow {
  int64_t index;
  std::vector<std::pair<std::string, double>> stages;
};

}  // namespace

RunSummary run(const PipelineSpec& spec, const registry::Registry& registry, const RunOptions& options) {
  (void)registry;
  const std::string out_dir = !options.output_dir.empty() ? options.output_dir : spec.output.dir;
  if (out_dir.empty()) throwAt(spec.path, "no output folder: set output.dir or pass --out DIR");

  datasets::DatasetOptions dopt;
  dopt.type = spec.dataset.type;
  dopt.root = spec.dataset.root;
  dopt.sequence = spec.dataset.sequence;
  if (spec.dataset.type == "synth") {
    const SynthSource source = synthSource(spec.dataset);
    if (options.progress) std::cerr << "synthetic sequence " << source.name << " (cached in " << spec.dataset.root << ")\n";
    dopt.type = "kitti_odometry";
    dopt.root = sim::ensureSequence(spec.dataset.root, source.config, source.name,
                                    options.progress && isatty(STDERR_FILENO) ? &std::cerr : nullptr);
    dopt.sequence = source.config.sequence;
  }
  dopt.camera = spec.dataset.camera;
  dopt.load_color = spec.dataset.color;
  dopt.load_lidar = spec.dataset.lidar;
  dopt.first = spec.dataset.first;
  dopt.last = spec.dataset.last;
  dopt.step = spec.dataset.step;
  dopt.ego_poses = spec.dataset.ego_poses;
  std::unique_ptr<datasets::Dataset> dataset = datasets::openDataset(dopt);
  if (dataset->size() == 0) throw Error(dataset->describe() + ": no frames in the selected range");

  makeDirectories(out_dir);
  if (spec.output.masks) makeDirectories((fs::path(out_dir) / "masks").string());

  registry::HostLog log(options.log_level);
  beslam_create_info base{};
  base.struct_size = sizeof(base);
  base.host = log.host();
  const datasets::Camera& camera = dataset->camera();
  base.camera.struct_size = sizeof(beslam_camera);
  base.camera.width = camera.width;
  base.camera.height = camera.height;
  base.camera.fx = camera.fx;
  base.camera.fy = camera.fy;
  base.camera.cx = camera.cx;
  base.camera.cy = camera.cy;
  if (const auto T = dataset->T_cam_lidar()) {
    base.has_lidar_extrinsics = 1;
    base.T_cam_lidar = sdk::toPose(*T);
  }
  const std::string abs_out = fs::absolute(out_dir).string();
  base.output_dir = abs_out.c_str();
  base.camera_height = spec.dataset.camera_height > 0 ? spec.dataset.camera_height : dataset->cameraHeight().value_or(0);

  auto infoFor = [&](const SlotSpec& slot) {
    beslam_create_info info = base;
    info.config = slot.config.values().data();
    info.config_count = static_cast<uint32_t>(slot.config.values().size());
    return info;
  };
  auto slot = [&](const char* name) -> const SlotSpec& { return spec.slots.at(name); };
  auto used = [&](const char* name) { return slot(name).plugin != nullptr; };

  std::unique_ptr<registry::DetectorInstance> detector;
  std::unique_ptr<registry::MotionCheckerInstance> motion;
  std::unique_ptr<registry::MaskGeneratorInstance> masker;
  std::unique_ptr<registry::ReconstructorInstance> reconstructor;
  if (!used("backend")) throwAt(spec.path, "backend: no plugin resolved");
  if (used("detector")) detector = std::make_unique<registry::DetectorInstance>(*slot("detector").plugin, infoFor(slot("detector")), log);
  if (used("motion_checker"))
    motion = std::make_unique<registry::MotionCheckerInstance>(*slot("motion_checker").plugin, infoFor(slot("motion_checker")), log);
  if (used("mask_generator"))
    masker = std::make_unique<registry::MaskGeneratorInstance>(*slot("mask_generator").plugin, infoFor(slot("mask_generator")), log);
  if (used("reconstructor"))
    reconstructor = std::make_unique<registry::ReconstructorInstance>(*slot("reconstructor").plugin, infoFor(slot("reconstructor")), log);
  auto backend = std::make_unique<registry::BackendInstance>(*slot("backend").plugin, infoFor(slot("backend")), log);

  RunSummary summary;
  summary.output_dir = out_dir;
  summary.camera_height = base.camera_height;
  bool world_metric = false;  // the backend's world unit, as its last track() said (data.h)
  std::map<std::string, double> counter_sums;
  std::vector<TimingRow> timings;
  std::vector<std::string> object_rows;
  std::vector<double> frame_ms;
  std::vector<int64_t> frame_indices;
  const bool tty = options.progress && isatty(STDERR_FILENO);
  const size_t n = dataset->size();

  for (size_t i = 0; i < n; ++i) {
    const auto t_frame = Clock::now();
    TimingRow timing;
    auto t0 = Clock::now();
    const datasets::Frame frame = dataset->load(i);
    timing.index = frame.index;
    timing.stages.emplace_back("load", msSince(t0));

    beslam_frame cf{};
    cf.struct_size = sizeof(cf);
    cf.index = frame.index;
    cf.timestamp = frame.timestamp;
    cf.gray = sdk::toView(frame.gray, BESLAM_PIXEL_GRAY8);
    cf.color = sdk::toView(frame.color, BESLAM_PIXEL_BGR8);
    if (!frame.lidar_xyzi.empty()) {
      cf.lidar.data = frame.lidar_xyzi.data();
      cf.lidar.count = frame.lidar_xyzi.size() / 4;
      cf.lidar.stride_bytes = 4 * sizeof(float);
    }
    cf.image_path = frame.image_path.c_str();

    t0 = Clock::now();
    const std::optional<Eigen::Isometry3d> T_world_cam_predicted = backend->predictPose(cf);
    timing.stages.emplace_back("predict", msSince(t0));

    std::vector<beslam_box3d> boxes;
    if (detector) {
      t0 = Clock::now();
      boxes = detector->detect(cf);
      checkBoxes(boxes, detector->plugin(), frame);
      timing.stages.emplace_back("detector", msSince(t0));
    }
    if (motion) {
      t0 = Clock::now();
      // A pose in an unknown unit would make parked cars seem to move (and cars keeping pace with the
      // ego seem parked): the checker gets none until the backend's world is metric.
      motion->classify(cf, world_metric ? T_world_cam_predicted : std::nullopt, boxes);
      timing.stages.emplace_back("motion_checker", msSince(t0));
    }
    for (const beslam_box3d& b : boxes)
      ++(b.motion_state == BESLAM_MOTION_STATIC    ? summary.detections_static
         : b.motion_state == BESLAM_MOTION_DYNAMIC ? summary.detections_dynamic
                                                   : summary.detections_unknown);
    cv::Mat mask;
    if (masker) {
      t0 = Clock::now();
      mask = cv::Mat::zeros(camera.height, camera.width, CV_16UC1);
      beslam_mask_buffer buffer{reinterpret_cast<uint16_t*>(mask.data), mask.cols, mask.rows,
                                static_cast<int32_t>(mask.step[0]), 0};
      masker->generate(cf, boxes, buffer);
      timing.stages.emplace_back("mask_generator", msSince(t0));
      if (cv::countNonZero(mask) > 0) ++summary.frames_with_masks;
    }
    const beslam_image_view mask_view = sdk::toView(mask, BESLAM_PIXEL_LABEL16);

    t0 = Clock::now();
    const registry::TrackOutput tracked = backend->track(cf, mask_view, boxes);
    timing.stages.emplace_back("backend", msSince(t0));
    for (const auto& [name, ms] : tracked.stage_ms) timing.stages.emplace_back("backend." + name, ms);
    if (tracked.result.state == BESLAM_TRACKING_OK) ++summary.tracked_online;
    frame_indices.push_back(frame.index);
    for (const auto& [name, value] : tracked.counters) counter_sums[name] += value;
    // The unit follows the backend's latest word (a reset map is unknown again); the summary keeps the frame
    // from which the world stayed metric.
    if (tracked.worldIsMetric() != world_metric) {
      world_metric = tracked.worldIsMetric();
      summary.metric_from_frame = world_metric ? frame.index : -1;
    }

    // Objects are reconstructed in metres only: nothing before the world is metric.
    if (reconstructor && tracked.result.is_keyframe && world_metric) {
      t0 = Clock::now();
      beslam_keyframe kf{};
      kf.struct_size = sizeof(kf);
      kf.id = tracked.result.keyframe_id;
      kf.frame_index = frame.index;
      kf.timestamp = frame.timestamp;
      kf.T_world_cam = tracked.result.T_world_cam;
      kf.world_scale = BESLAM_WORLD_SCALE_METRIC;
      const registry::Landmarks landmarks = reconstructor->reconstruct(kf, cf, boxes, mask_view);
      if (!landmarks.landmarks.empty()) backend->addLandmarks(landmarks);
      timing.stages.emplace_back("reconstructor", msSince(t0));
    }

    if (detector)
      for (const beslam_box3d& b : boxes) object_rows.push_back(formatObjectRow(frame.index, b, base.camera));
    if (spec.output.masks) {
      const std::string path = (fs::path(out_dir) / "masks" / (std::to_string(1000000 + frame.index).substr(1) + ".png")).string();
      std::vector<uchar> png;
      if (!cv::imencode(".png", mask.empty() ? cv::Mat::zeros(camera.height, camera.width, CV_16UC1) : mask, png))
        throwAt(path, "cannot encode mask");
      writeFileAtomic(path, std::string(png.begin(), png.end()));
    }

    const double total = msSince(t_frame);
    timing.stages.emplace_back("total", total);
    frame_ms.push_back(total);
    timings.push_back(std::move(timing));
    if (tty) std::cerr << "\rframe " << (i + 1) << "/" << n << std::flush;
  }
  if (tty) std::cerr << "\n";

  backend->finish();
  summary.frames = static_cast<int64_t>(n);
  const auto final_poses = backend->trajectory(BESLAM_TRAJECTORY_FINAL);
  const auto online_poses = backend->trajectory(BESLAM_TRAJECTORY_ONLINE);
  const auto keyframe_poses = backend->trajectory(BESLAM_TRAJECTORY_KEYFRAMES);
  summary.keyframes = static_cast<int64_t>(keyframe_poses.size());
  {  // a frame counts as tracked when the backend's final trajectory has it (an initialisation
     // reference frame gets its pose once the map exists)
    std::vector<int64_t> in_final;
    for (const auto& p : final_poses) in_final.push_back(p.frame_index);
    std::sort(in_final.begin(), in_final.end());
    for (int64_t index : frame_indices)
      if (std::binary_search(in_final.begin(), in_final.end(), index)) ++summary.tracked;
      else summary.untracked.push_back(index);
  }
  writeTrajectory(out_dir, "trajectory", final_poses, true);
  writeTrajectory(out_dir, "trajectory_online", online_poses, false);
  writeTrajectory(out_dir, "keyframes", keyframe_poses, false);
  {
    const auto points = backend->mapPoints();
    summary.map_points = static_cast<int64_t>(points.size());
    for (const auto& p : points) summary.map_points_static += (p.flags & BESLAM_MAP_POINT_STATIC_OBJECT) ? 1 : 0;
    if (spec.output.map_points && !points.empty()) writePly((fs::path(out_dir) / "map_points.ply").string(), points);
  }
  summary.backend_counters.assign(counter_sums.begin(), counter_sums.end());
  if (detector) {
    writeFileAtomic((fs::path(out_dir) / "objects.txt").string(), [&](std::ostream& out) {
      for (const auto& row : object_rows) out << row << '\n';
    });
  }

  {  // resolved pipeline
    YAML::Emitter emitter;
    emitter << spec.document;
    writeFileAtomic((fs::path(out_dir) / "pipeline.resolved.yaml").string(),
                    "# " + spec.path + " as run, with every default filled in\n" + std::string(emitter.c_str()) + "\n");
  }

  {  // timing.csv: one row a frame, one column a stage (ms); stages a frame skipped are empty
    std::vector<std::string> columns;
    for (const auto& row : timings)
      for (const auto& [name, ms] : row.stages)
        if (std::find(columns.begin(), columns.end(), name) == columns.end()) columns.push_back(name);
    writeFileAtomic((fs::path(out_dir) / "timing.csv").string(), [&](std::ostream& out) {
      out << "frame";
      for (const auto& c : columns) out << ',' << c << "_ms";
      out << '\n' << std::fixed << std::setprecision(3);
      for (const auto& row : timings) {
        out << row.index;
        for (const auto& c : columns) {
          out << ',';
          double sum = 0;
          bool any = false;
          for (const auto& [name, ms] : row.stages)
            if (name == c) sum += ms, any = true;
          if (any) out << sum;
        }
        out << '\n';
      }
    });
  }

  summary.median_frame_ms = median(frame_ms);
  nlohmann::json json;
  json["pipeline"] = spec.path;
  json["dataset"] = dataset->describe();
  if (dopt.type == "kitti_odometry") {  // where truth files of a synthetic sequence are (beslam eval-motion)
    json["dataset_path"] = fs::absolute(fs::path(dopt.root) / "sequences" / dopt.sequence).string();
    json["dataset_sequence"] = dopt.sequence;
  }
  json["frames"] = summary.frames;
  json["tracked"] = summary.tracked;
  json["tracked_when_seen"] = summary.tracked_online;
  json["untracked_frames"] = summary.untracked;
  json["keyframes"] = summary.keyframes;
  json["median_frame_ms"] = summary.median_frame_ms;
  for (const auto& [name, s] : spec.slots)
    json["plugins"][name] = s.plugin ? nlohmann::json(s.plugin->id + " " + s.plugin->version) : nlohmann::json(nullptr);
  json["world"] = {{"metric", summary.metric_from_frame >= 0},
                   {"metric_from_frame", summary.metric_from_frame >= 0 ? nlohmann::json(summary.metric_from_frame)
                                                                         : nlohmann::json(nullptr)},
                   {"camera_height_m", summary.camera_height > 0 ? nlohmann::json(summary.camera_height)
                                                                  : nlohmann::json(nullptr)}};
  json["detections"] = {{"static", summary.detections_static},
                        {"dynamic", summary.detections_dynamic},
                        {"unknown", summary.detections_unknown}};
  json["frames_with_masks"] = summary.frames_with_masks;
  json["map_points"] = {{"total", summary.map_points}, {"on_static_objects", summary.map_points_static}};
  json["backend_counters"] = nlohmann::json::object();
  for (const auto& [name, value] : summary.backend_counters) json["backend_counters"][name] = value;

  if (spec.evaluation.enabled && !final_poses.empty()) {
    if (const auto gt = dataset->groundTruth()) {
      trajectory::Trajectory est;
      for (const auto& p : final_poses) est.push_back(p.timestamp, p.T_world_cam);
      eval::EvalOptions eopt;
      eopt.format = "tum";
      eopt.alignment = eval::parseAlignmentType(spec.evaluation.alignment);
      eopt.delta = static_cast<std::size_t>(spec.evaluation.rpe_delta);
      try {
        const eval::PairedTrajectories paired = eval::associateByTime(*gt, est, 1e-3);
        const eval::EvalResult result = eval::evaluatePaired(paired.ref, paired.est, eopt);
        summary.has_ape = true;
        summary.ape_trans_rmse = result.ape.trans.rmse;
        summary.rpe_trans_rmse = result.rpe.trans.rmse;
        summary.ape_alignment_scale = result.alignment.scale;
        json["evaluation"] = nlohmann::json::parse(eval::toJson(result));
        // Both alignments side by side: with a metric map, SE(3) APE close to Sim(3) APE says the scale is right.
        auto with = [&](eval::AlignmentType type) {  // the configured alignment is already evaluated
          if (eopt.alignment == type) return result;
          eval::EvalOptions o = eopt;
          o.alignment = type;
          return eval::evaluatePaired(paired.ref, paired.est, o);
        };
        const eval::EvalResult r_sim3 = with(eval::AlignmentType::kSim3);
        const eval::EvalResult r_se3 = with(eval::AlignmentType::kSe3);
        summary.ape_sim3_rmse = r_sim3.ape.trans.rmse;
        summary.ape_se3_rmse = r_se3.ape.trans.rmse;
        json["ape"] = {{"sim3_rmse", r_sim3.ape.trans.rmse},
                       {"sim3_scale", r_sim3.alignment.scale},
                       {"se3_rmse", r_se3.ape.trans.rmse}};
      } catch (const Error& e) {
        // A degenerate or too short trajectory cannot be aligned: the run is still good, say why.
        summary.evaluation_error = e.what();
        json["evaluation"] = {{"error", e.what()}};
      }
    }
  }
  writeFileAtomic((fs::path(out_dir) / "summary.json").string(), json.dump(2) + "\n");
  return summary;
}

}  // namespace beslam::pipeline
