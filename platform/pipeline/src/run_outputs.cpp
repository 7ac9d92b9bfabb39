#include "run_outputs.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <ostream>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/memory.hpp"
#include "beslam/eval/eval.hpp"
#include "beslam/trajectory/trajectory.hpp"

namespace fs = std::filesystem;

namespace beslam::pipeline::detail {

namespace {

trajectory::Trajectory toTrajectory(const std::vector<registry::PoseEntry>& poses) {
  trajectory::Trajectory t;
  for (const auto& p : poses) t.push_back(p.timestamp, p.T_world_cam);
  return t;
}

void writeTrajectory(const std::string& dir, const std::string& stem, const std::vector<registry::PoseEntry>& poses,
                     bool kitti_too) {
  const trajectory::Trajectory t = toTrajectory(poses);
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

// timing.csv: one row a frame, one column a stage (ms); stages a frame skipped are empty. A last column,
// rss_mb, holds the resident memory at each frame's end when the runner measured it.
void writeTimingCsv(const std::string& path, const std::vector<TimingRow>& timings) {
  std::vector<std::string> columns;
  bool rss = false;
  for (const auto& row : timings) {
    rss = rss || row.rss_mb > 0;
    for (const auto& stage : row.stages)
      if (std::find(columns.begin(), columns.end(), stage.first) == columns.end()) columns.push_back(stage.first);
  }
  writeFileAtomic(path, [&](std::ostream& out) {
    out << "frame";
    for (const auto& c : columns) out << ',' << c << "_ms";
    if (rss) out << ",rss_mb";
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
      if (rss) out << ',' << std::setprecision(1) << row.rss_mb << std::setprecision(3);
      out << '\n';
    }
  });
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

nlohmann::json orNull(bool present, const nlohmann::json& value) { return present ? value : nlohmann::json(nullptr); }

// APE/RPE with the configured alignment, plus Sim(3) and SE(3) APE side by side: with a metric map,
// SE(3) APE close to Sim(3) APE says the scale is right.
void evaluate(const PipelineSpec& spec, datasets::Dataset& dataset, const std::vector<registry::PoseEntry>& final_poses,
              RunSummary& summary, nlohmann::json& json) {
  if (!spec.evaluation.enabled || final_poses.empty()) return;
  const auto gt = dataset.groundTruth();
  if (!gt) return;
  const trajectory::Trajectory est = toTrajectory(final_poses);
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
    // SE(3) APE measures the trajectory in metres: a map that never became metric has none (its unit against
    // metres would be a number without meaning), and says null.
    json["ape"] = {{"sim3_rmse", r_sim3.ape.trans.rmse},
                   {"sim3_scale", r_sim3.alignment.scale},
                   {"se3_rmse", orNull(summary.metric_from_frame >= 0, r_se3.ape.trans.rmse)}};
  } catch (const Error& e) {
    // A degenerate or too short trajectory cannot be aligned: the run is still good, say why.
    summary.evaluation_error = e.what();
    json["evaluation"] = {{"error", e.what()}};
  }
}

// What a run writes into its folder (and --overwrite removes): files, then folders.
const char* const kRunFiles[] = {
    "summary.json",           "trajectory.tum", "trajectory.kitti", "trajectory_online.tum", "keyframes.tum",
    "pipeline.resolved.yaml", "timing.csv",     "objects.txt",      "objects.json",          "map.ply",
    "map_points.ply",         "static_map.bt",  "frames.csv"};
const char* const kRunFolders[] = {"masks", "samples", "objects"};

std::string share(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

// Why a run tracked too little, from what the host saw: the frames in the backend's final trajectory (sorted),
// the frames processed in order, and the backend's summed "features" counter (its keypoints a frame).
std::string trackingFailureReason(const std::vector<int64_t>& in_final, const std::vector<int64_t>& frames,
                                  const std::map<std::string, double>& counters) {
  if (in_final.empty()) {
    const auto features = counters.find("features");
    if (features != counters.end() && !frames.empty()) {
      const double per_frame = features->second / static_cast<double>(frames.size());
      if (per_frame < 100)
        return "never initialised: too few features (" + share(std::round(per_frame)) +
               " a frame; a blank, dark or mostly masked image)";
      return "never initialised with " + share(std::round(per_frame)) +
             " features a frame: too little parallax or too few matches between frames (a camera that barely "
             "moves, or one too fast for its frame rate)";
    }
    return "never initialised";
  }
  // The first frame after the first tracked one that the final trajectory lacks, with nothing tracked after.
  const int64_t last_tracked = in_final.back();
  for (int64_t index : frames)
    if (index > last_tracked) return "lost at frame " + std::to_string(index) + ", not found again";
  return "initialised only at frame " + std::to_string(in_final.front());
}

}  // namespace

OutputLock::OutputLock(const std::string& out_dir) {
  fd_ = ::open(out_dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0) throwAt(out_dir, std::string("cannot open the output folder: ") + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    if (e == EWOULDBLOCK)
      throwAt(out_dir, "another beslam run is writing into this folder (locked); wait for it or choose another --out");
    throwAt(out_dir, std::string("cannot lock the output folder: ") + std::strerror(e));
  }
}

OutputLock::~OutputLock() {
  if (fd_ >= 0) ::close(fd_);
}

void claimOutputFolder(const std::string& out_dir, bool overwrite) {
  const fs::path dir(out_dir);
  std::error_code ec;
  std::string used;
  for (const char* f : {"summary.json", "trajectory.tum", "trajectory.kitti"})
    if (used.empty() && fs::exists(dir / f, ec)) used = f;
  if (used.empty()) return;
  if (!overwrite)
    throwAt(out_dir,
            "holds a previous run's outputs (" + used + "); pass --overwrite to replace them, or choose another --out");
  for (const char* f : kRunFiles)
    if (fs::remove(dir / f, ec); ec) throwAt((dir / f).string(), "cannot remove (--overwrite): " + ec.message());
  for (const char* f : kRunFolders)
    if (fs::remove_all(dir / f, ec); ec) throwAt((dir / f).string(), "cannot remove (--overwrite): " + ec.message());
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {  // a killed run's temporaries
    const std::string name = it->path().filename().string();
    for (const char* f : kRunFiles)
      if (name.rfind(std::string(f) + ".tmp.", 0) == 0) fs::remove(it->path(), ec);
  }
}

namespace {

const char* trackingStateName(int32_t state) {
  switch (state) {
    case BESLAM_TRACKING_OK:
      return "ok";
    case BESLAM_TRACKING_LOST:
      return "lost";
    case BESLAM_TRACKING_NOT_INITIALIZED:
      return "not_initialised";
    default:
      return "unknown";
  }
}

}  // namespace

RunJournal::RunJournal(const std::string& out_dir) {
  tum_.path = (fs::path(out_dir) / "trajectory.tum").string();
  kitti_.path = (fs::path(out_dir) / "trajectory.kitti").string();
  frames_.path = (fs::path(out_dir) / "frames.csv").string();
  for (File* f : {&tum_, &kitti_, &frames_}) {
    f->fd = ::open(f->path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0644);
    if (f->fd < 0) {
      const int err = errno;
      close();
      throwAt(f->path, std::string("cannot create: ") + std::strerror(err));
    }
  }
  append(tum_, formats::kTumHeader);
  append(frames_, kFramesCsvHeader);
}

RunJournal::~RunJournal() { close(); }

void RunJournal::close() {
  for (File* f : {&tum_, &kitti_, &frames_}) {
    if (f->fd >= 0) ::close(f->fd);
    f->fd = -1;
  }
}

void RunJournal::addPose(double stamp, const Eigen::Isometry3d& T_world_cam) {
  append(tum_, formats::tumRow(stamp, T_world_cam));
  append(kitti_, formats::kittiRow(T_world_cam));
}

void RunJournal::addFrame(const FrameJournalRow& r) {
  std::ostringstream row;
  row << std::setprecision(17) << r.index << ',' << r.timestamp << std::setprecision(6) << ','
      << trackingStateName(r.state) << ',' << (r.keyframe ? 1 : 0) << ',' << r.tracked_points << ',';
  if (r.features >= 0) row << r.features;
  row << ',' << r.detections << ',' << r.detections_static << ',' << r.detections_dynamic << ',' << r.detections_unknown
      << ',' << (r.masked ? 1 : 0) << ',' << (r.metric ? 1 : 0) << '\n';
  append(frames_, row.str());
}

void RunJournal::append(File& file, const std::string& row) {
  if (file.fd < 0) return;
  size_t done = 0;
  while (done < row.size()) {
    const ssize_t n = ::write(file.fd, row.data() + done, row.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      std::cerr << "warning: " << file.path << ": cannot append the frame's row (" << std::strerror(errno)
                << (&file == &frames_ ? "); frames.csv stops here\n"
                                      : "); the trajectory is written again at the end of the run\n");
      ::close(file.fd);
      file.fd = -1;
      return;
    }
    done += static_cast<size_t>(n);
  }
}

void writeFailureSummary(const PipelineSpec& spec, const std::string& out_dir, const DatasetRecord& dataset_record,
                         const RunSummary& summary, int64_t frames, const std::string& reason) {
  nlohmann::json json;
  json["pipeline"] = spec.path;
  json["dataset"] = dataset_record.description;
  json["status"] = "failed: " + reason;
  json["frames"] = frames;
  json["interrupted"] = false;
  json["last_frame"] = orNull(frames > 0, summary.last_frame);
  json["tracked_when_seen"] = summary.tracked_online;
  json["trajectory"] = "trajectory.tum and trajectory.kitti hold the poses of the tracked frames done, as tracked";
  writeFileAtomic((fs::path(out_dir) / "summary.json").string(), json.dump(2) + "\n");
}

void writeRunOutputs(const PipelineSpec& spec, const std::string& out_dir, const DatasetRecord& dataset_record,
                     datasets::Dataset& dataset, registry::BackendInstance& backend, const RunRecord& record,
                     static_map::StaticMapBuilder* static_map, RunSummary& summary) {
  const fs::path dir(out_dir);
  summary.frames = static_cast<int64_t>(record.frame_indices.size());
  const auto final_poses = backend.trajectory(BESLAM_TRAJECTORY_FINAL);
  const auto online_poses = backend.trajectory(BESLAM_TRAJECTORY_ONLINE);
  const auto keyframe_poses = backend.trajectory(BESLAM_TRAJECTORY_KEYFRAMES);
  summary.keyframes = static_cast<int64_t>(keyframe_poses.size());
  // A frame counts as tracked when the backend's final trajectory has it (an initialisation reference frame
  // gets its pose once the map exists).
  std::vector<int64_t> in_final;
  for (const auto& p : final_poses) in_final.push_back(p.frame_index);
  std::sort(in_final.begin(), in_final.end());
  for (int64_t index : record.frame_indices)
    if (std::binary_search(in_final.begin(), in_final.end(), index))
      ++summary.tracked;
    else
      summary.untracked.push_back(index);
  summary.status = summary.interrupted ? "interrupted" : "completed";
  if (!summary.interrupted && summary.frames > 0 &&
      static_cast<double>(summary.tracked) < spec.output.min_tracked_share * static_cast<double>(summary.frames))
    summary.status = "failed: tracked " + std::to_string(summary.tracked) + " of " + std::to_string(summary.frames) +
                     " frames (" + trackingFailureReason(in_final, record.frame_indices, record.counter_sums) +
                     "), fewer than output.min_tracked_share " + share(spec.output.min_tracked_share) +
                     " (lower it for a pipeline that tracks part of a sequence)";
  writeTrajectory(out_dir, "trajectory", final_poses, true);
  writeTrajectory(out_dir, "trajectory_online", online_poses, false);
  writeTrajectory(out_dir, "keyframes", keyframe_poses, false);
  const auto points = backend.mapPoints();
  summary.map_points = static_cast<int64_t>(points.size());
  for (const auto& p : points) summary.map_points_static += (p.flags & BESLAM_MAP_POINT_STATIC_OBJECT) ? 1 : 0;
  if (spec.output.map_points && !points.empty()) writePly((dir / "map_points.ply").string(), points);
  nlohmann::json static_map_json;
  if (static_map) {  // static_map.bt from the final poses
    std::map<int64_t, Eigen::Isometry3d> T_world_cam;
    for (const auto& p : final_poses) T_world_cam[p.frame_index] = p.T_world_cam;
    std::vector<Eigen::Vector3d> p_world, keyframe_centres;
    for (const auto& p : points) p_world.emplace_back(p.p_world[0], p.p_world[1], p.p_world[2]);
    for (const auto& k : keyframe_poses) keyframe_centres.push_back(k.T_world_cam.translation());
    const auto tree = static_map->build(T_world_cam, p_world, keyframe_centres);
    static_map::writeTree(*tree, (dir / "static_map.bt").string());
    const static_map::Stats& st = static_map->stats();
    static_map_json = {{"file", "static_map.bt"},
                       {"resolution_m", tree->getResolution()},
                       {"source", st.scans > 0 ? "lidar" : "map_points"},
                       {"scans", st.scans},
                       {"points_inserted", st.scans > 0 ? st.points_inserted : st.map_points},
                       {"points_in_boxes_not_static", st.points_in_boxes},
                       {"points_outside_view", st.points_outside_view},
                       {"leaf_nodes", tree->getNumLeafNodes()}};
  }
  summary.backend_counters.assign(record.counter_sums.begin(), record.counter_sums.end());
  summary.loop_closures = record.loop_closures;
  summary.relocalisation_frames = record.relocalisation_frames;
  if (spec.slots.at("detector").plugin)
    writeFileAtomic((dir / "objects.txt").string(), [&](std::ostream& out) {
      for (const auto& row : record.object_rows) out << row << '\n';
    });
  {
    YAML::Emitter emitter;
    emitter << spec.document;
    writeFileAtomic((dir / "pipeline.resolved.yaml").string(),
                    "# " + spec.path + " as run, with every default filled in\n" + std::string(emitter.c_str()) + "\n");
  }
  writeTimingCsv((dir / "timing.csv").string(), record.timings);

  summary.median_frame_ms = median(record.frame_ms);
  nlohmann::json json;
  json["pipeline"] = spec.path;
  json["dataset"] = dataset_record.description;
  if (!dataset_record.kitti_root.empty()) {  // where truth files of a synthetic sequence are (beslam eval-motion)
    json["dataset_path"] =
        fs::absolute(fs::path(dataset_record.kitti_root) / "sequences" / dataset_record.kitti_sequence).string();
    json["dataset_sequence"] = dataset_record.kitti_sequence;
  }
  json["status"] = summary.status;
  json["frames"] = summary.frames;
  json["interrupted"] = summary.interrupted;
  json["last_frame"] = orNull(!record.frame_indices.empty(), summary.last_frame);
  if (summary.interrupted) json["interrupted_by"] = summary.interrupted_by;
  json["tracked"] = summary.tracked;
  json["tracked_when_seen"] = summary.tracked_online;
  json["untracked_frames"] = summary.untracked;
  json["keyframes"] = summary.keyframes;
  json["median_frame_ms"] = summary.median_frame_ms;
  json["fps"] = summary.fps;
  for (const auto& [name, s] : spec.slots)
    json["plugins"][name] = s.plugin ? nlohmann::json(s.plugin->id + " " + s.plugin->version) : nlohmann::json(nullptr);
  json["world"] = {{"metric", summary.metric_from_frame >= 0},
                   {"metric_from_frame", orNull(summary.metric_from_frame >= 0, summary.metric_from_frame)},
                   {"camera_height_m", orNull(summary.camera_height > 0, summary.camera_height)},
                   {"motion_replayed_frames", summary.motion_replayed_frames},
                   {"motion_replay", spec.run.motion_replay_boxes ? "boxes" : "poses"},
                   {"moves", summary.world_moves}};
  json["detections"] = {{"static", summary.detections_static},
                        {"dynamic", summary.detections_dynamic},
                        {"unknown", summary.detections_unknown}};
  json["frames_with_masks"] = summary.frames_with_masks;
  json["map_points"] = {{"total", summary.map_points}, {"on_static_objects", summary.map_points_static}};
  if (static_map) json["static_map"] = static_map_json;
  json["objects"] = nullptr;
  if (record.has_reconstructor) {
    ObjectMap objects = record.objects;
    followFinalPoses(objects, record.anchors, final_poses);  // loop corrections after an object was fitted
    json["objects"] = writeObjectOutputs(out_dir, objects, points);
    summary.objects_reconstructed = json["objects"]["reconstructed"].get<int64_t>();
    summary.objects_with_mesh = json["objects"]["with_mesh"].get<int64_t>();
  }
  json["backend_counters"] = nlohmann::json::object();
  for (const auto& [name, value] : summary.backend_counters) json["backend_counters"][name] = value;
  json["loop_closure_frames"] = nlohmann::json::array();
  for (const auto& l : summary.loop_closures)
    json["loop_closure_frames"].push_back({{"frame", l.frame}, {"correction", l.correction}});
  json["relocalisation_frames"] = summary.relocalisation_frames;
  evaluate(spec, dataset, final_poses, summary, json);
  summary.peak_rss_mb = peakResidentMemoryMb();  // after the objects' meshes and the evaluation
  json["peak_rss_mb"] = summary.peak_rss_mb;
  writeFileAtomic((dir / "summary.json").string(), json.dump(2) + "\n");
}

}  // namespace beslam::pipeline::detail
