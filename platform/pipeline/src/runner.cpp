#include "beslam/pipeline/runner.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <sstream>
#include <thread>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/memory.hpp"
#include "beslam/common/yaml_set.hpp"
#include "beslam/datasets/dataset.hpp"
#include "beslam/formats/geometry.hpp"
#include "beslam/pipeline/objects.hpp"
#include "beslam/registry/instance.hpp"
#include "beslam/sdk/views.hpp"  // the host uses the SDK's zero-copy view helpers too
#include "beslam/sim/synth.hpp"
#include "run_outputs.hpp"
#include "sample_frames.hpp"

namespace fs = std::filesystem;

namespace beslam::pipeline {

namespace {

using Clock = std::chrono::steady_clock;

// Times one stage into a frame's timing row: `auto t = timer("detector"); ...` records on scope exit.
class StageTimer {
 public:
  StageTimer(detail::TimingRow& row, std::string name) : row_(row), name_(std::move(name)), t0_(Clock::now()) {}
  ~StageTimer() {
    row_.stages.emplace_back(std::move(name_), std::chrono::duration<double, std::milli>(Clock::now() - t0_).count());
  }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  detail::TimingRow& row_;
  std::string name_;
  Clock::time_point t0_;
};

// Boxes from a detector must be finite and sized before any other plugin sees them; the boxes a motion checker
// hands on are checked again (it writes into them in place: a faulty one must not reach the backend).
void checkBoxes(const std::vector<beslam_box3d>& boxes, const registry::Plugin& plugin, const datasets::Frame& frame) {
  for (size_t i = 0; i < boxes.size(); ++i) {
    const beslam_box3d& b = boxes[i];
    const char* bad = nullptr;
    for (double v : b.center_cam) bad = std::isfinite(v) ? bad : "a non-finite centre";
    for (double v : b.size)
      bad = bad ? bad : (std::isfinite(v) && v > 0 ? nullptr : "a non-finite or non-positive size");
    if (!bad && !std::isfinite(b.yaw)) bad = "a non-finite yaw";
    if (!bad && !std::isfinite(b.score)) bad = "a non-finite score";
    if (!bad && (b.flags & BESLAM_BOX_HAS_VELOCITY))
      for (double v : b.velocity_cam) bad = std::isfinite(v) ? bad : "a non-finite velocity";
    if (!bad && (b.flags & BESLAM_BOX_HAS_POSITION_SIGMA))
      for (double v : {b.position_sigma[0], b.position_sigma[1], b.range_drift})
        bad = bad ? bad : (std::isfinite(v) && v >= 0 ? nullptr : "a non-finite or negative position sigma");
    if (bad)
      throw Error("plugin " + plugin.id + " (" + plugin.library_path + "): frame " + std::to_string(frame.index) +
                  " (" + frame.image_path + "): box " + std::to_string(i) + " has " + bad);
  }
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

// The ABI view of a loaded frame (it points into the frame, which must outlive it).
beslam_frame frameView(const datasets::Frame& frame) {
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
  return cf;
}

// A frame the motion checker saw without a pose (the world not metric yet), kept so that a new checker
// can be run on it once the backend's poses are metric (runner.hpp).
struct UnposedFrame {
  datasets::Frame frame;            // shares its images with the frame that was processed
  std::vector<beslam_box3d> boxes;  // as the detector gave them
};

// Everything one frame carries from stage to stage.
struct FrameState {
  size_t position = 0;  // in the selected range
  datasets::Frame frame;
  beslam_frame view{};  // the ABI view of `frame` (points into it)
  std::optional<Eigen::Isometry3d> T_world_cam_predicted;
  std::vector<beslam_box3d> boxes;
  cv::Mat mask;              // CV_16UC1 labels, empty without a mask generator
  bool mask_marked = false;  // the mask marks some pixel
  registry::TrackOutput tracked;
  detail::TimingRow timing;
  std::exception_ptr error;  // what preparing the frame threw (rethrown when its turn comes)
};

// Frames prepared ahead on one producer thread, handed over in order through a bounded queue. Each frame
// is prepared by `prepare` (always from the producer thread, frame after frame), so every plugin that
// `prepare` calls still sees the frames one at a time and in order. A frame whose preparation threw
// carries the exception and ends production; next() rethrows it when that frame's turn comes, after the
// frames before it were handed over, as the sequential loop would. The destructor stops the producer
// (after the call in progress) and joins it.
class Prefetcher {
 public:
  Prefetcher(size_t frames, size_t capacity, std::function<void(size_t, FrameState&)> prepare)
      : frames_(frames), capacity_(std::max<size_t>(capacity, 1)), prepare_(std::move(prepare)) {
    thread_ = std::thread([this] { produce(); });
  }
  ~Prefetcher() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  Prefetcher(const Prefetcher&) = delete;
  Prefetcher& operator=(const Prefetcher&) = delete;

  // The next frame in order (blocks until it is ready).
  std::unique_ptr<FrameState> next() {
    std::unique_ptr<FrameState> f;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return !queue_.empty(); });
      f = std::move(queue_.front());
      queue_.pop_front();
    }
    cv_.notify_all();
    if (f->error) std::rethrow_exception(f->error);
    return f;
  }

 private:
  void produce() {
    for (size_t i = 0; i < frames_; ++i) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [this] { return stop_ || queue_.size() < capacity_; });
        if (stop_) return;
      }
      auto f = std::make_unique<FrameState>();
      try {
        prepare_(i, *f);
      } catch (...) {
        f->error = std::current_exception();
      }
      const bool failed = static_cast<bool>(f->error);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        queue_.push_back(std::move(f));
      }
      cv_.notify_all();
      if (failed) return;
    }
  }

  const size_t frames_, capacity_;
  std::function<void(size_t, FrameState&)> prepare_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::unique_ptr<FrameState>> queue_;
  bool stop_ = false;
  std::thread thread_;  // last: starts once everything above exists
};

// One run: the plugins, the dataset and what the frame loop gathers. The stages of a frame are the
// member functions load .. write, called in that order; data only flows forward through FrameState.
class Run {
 public:
  Run(const PipelineSpec& spec, const RunOptions& options) : spec_(spec), options_(options), log_(options.log_level) {
    out_dir_ = !options.output_dir.empty() ? options.output_dir : spec.output.dir;
    if (out_dir_.empty()) throwAt(spec.path, "no output folder: set output.dir or pass --out DIR");
    makeDirectories(out_dir_);
    lock_ = std::make_unique<detail::OutputLock>(out_dir_);  // before anything is read or removed
    detail::claimOutputFolder(out_dir_, options.overwrite);
    openDataset();
    if (spec.output.masks) makeDirectories((fs::path(out_dir_) / "masks").string());
    sample_positions_ = detail::samplePositions(dataset_->size(), spec.output.samples);
    createPlugins();
    if (spec.output.octomap) {
      static_map::Options o;
      o.resolution = spec.output.octomap_resolution;
      o.camera = camera_;
      static_map_ = std::make_unique<static_map::StaticMapBuilder>(o);
    }
  }

  RunSummary execute() {
    journal_ = std::make_unique<detail::RunJournal>(out_dir_);
    try {
      runFrames();
      journal_->close();  // the final trajectory replaces its poses; frames.csv stays as it is
      detail::writeRunOutputs(spec_, out_dir_, dataset_record_, *dataset_, *backend_, record_, static_map_.get(),
                              summary_);
    } catch (const std::exception& e) {
      // What is done stays: the journal's poses, and a summary that says how far the run got and why it ended.
      try {
        detail::writeFailureSummary(spec_, out_dir_, dataset_record_, summary_,
                                    static_cast<int64_t>(record_.frame_indices.size()), e.what());
      } catch (const std::exception&) {  // the first error is the one to report
      }
      throw;
    }
    if (summary_.status.rfind("failed: ", 0) == 0)
      throwAt((fs::path(out_dir_) / "summary.json").string(), summary_.status.substr(8));
    return summary_;
  }

 private:
  void runFrames() {
    const bool tty = options_.progress && isatty(STDERR_FILENO);
    const size_t n = dataset_->size();
    // What may run ahead of the backend: loading and detection always (they see the frame only); the
    // mask only without a motion checker (the mask follows the motion states, which follow the backend's
    // predicted pose once the world is metric). Everything from classify on runs here, in frame order.
    const bool prefetch = spec_.run.prefetch > 0 && n > 1;
    mask_ahead_ = prefetch && !motion_;
    backend_ahead_ = prefetch && backend_->hasPrepare();
    std::unique_ptr<Prefetcher> prefetcher;
    if (prefetch)
      prefetcher = std::make_unique<Prefetcher>(n, static_cast<size_t>(spec_.run.prefetch),
                                                [this](size_t i, FrameState& f) { prepare(i, f); });
    const auto t_loop = Clock::now();
    size_t done = 0;
    for (size_t i = 0; i < n; ++i) {
      const auto t_frame = Clock::now();
      std::unique_ptr<FrameState> fp;
      if (prefetcher) {
        fp = prefetcher->next();
      } else {
        fp = std::make_unique<FrameState>();
        prepare(i, *fp);
      }
      FrameState& f = *fp;
      predict(f);
      classify(f);
      if (!mask_ahead_) mask(f);
      if (f.mask_marked) ++summary_.frames_with_masks;
      track(f);
      if (f.tracked.result.state == BESLAM_TRACKING_OK)
        journal_->addPose(f.frame.timestamp, formats::toIsometry(f.tracked.result.T_world_cam));
      reconstruct(f);
      write(f);
      journalFrame(f);
      // A frame's total is its share of the loop's wall time: with prefetching, its load, detection and
      // mask overlapped the frame before and are not in it (their own columns still say what they cost).
      const double total = std::chrono::duration<double, std::milli>(Clock::now() - t_frame).count();
      f.timing.stages.emplace_back("total", total);
      f.timing.rss_mb = residentMemoryMb();
      record_.frame_ms.push_back(total);
      record_.timings.push_back(std::move(f.timing));
      summary_.last_frame = f.frame.index;
      ++done;
      if (tty) std::cerr << "\rframe " << (i + 1) << "/" << n << std::flush;
      if (options_.after_frame) options_.after_frame(f.frame.index);
      if (options_.stop_requested && options_.stop_requested()) {
        summary_.interrupted = true;
        summary_.interrupted_by = options_.stop_reason ? options_.stop_reason() : "stop requested";
        break;
      }
    }
    prefetcher.reset();  // stops loading ahead (an interrupted run) and joins the producer
    const double loop_s = std::chrono::duration<double>(Clock::now() - t_loop).count();
    summary_.fps = loop_s > 0 ? static_cast<double>(done) / loop_s : 0;
    if (tty) std::cerr << "\n";
    if (reconstructor_) {  // its last updates go to the backend before the backend's final optimisation
      const registry::Landmarks last = reconstructor_->finish();
      detail::applyLandmarkUpdates(record_.objects, last);
      detail::anchorFinalUpdates(record_.anchors, last, keyframe_poses_given_);
      if (!last.empty()) backend_->addLandmarks(last);
    }
    backend_->finish();
  }

  void openDataset() {
    datasets::DatasetOptions dopt;
    dopt.type = spec_.dataset.type;
    dopt.root = spec_.dataset.root;
    dopt.sequence = spec_.dataset.sequence;
    if (spec_.dataset.type == "synth") {
      const SynthSource source = synthSource(spec_.dataset);
      if (options_.progress)
        std::cerr << "synthetic sequence " << source.name << " (cached in " << spec_.dataset.root << ")\n";
      dopt.type = "kitti_odometry";
      dopt.root = sim::ensureSequence(spec_.dataset.root, source.config, source.name,
                                      options_.progress && isatty(STDERR_FILENO) ? &std::cerr : nullptr);
      dopt.sequence = source.config.sequence;
      dopt.name = "synthetic " + source.name;  // not "KITTI odometry 00": rendered, only laid out like KITTI
    }
    dopt.camera = spec_.dataset.camera;
    dopt.load_color = spec_.dataset.color;
    dopt.load_lidar = spec_.dataset.lidar;
    dopt.first = spec_.dataset.first;
    dopt.last = spec_.dataset.last;
    dopt.step = spec_.dataset.step;
    dopt.ego_poses = spec_.dataset.ego_poses;
    dopt.calibration = spec_.dataset.calibration;
    dataset_ = datasets::openDataset(dopt);
    if (!spec_.dataset.black_frames.empty()) {
      try {
        dataset_ = datasets::blackOut(std::move(dataset_), spec_.dataset.black_frames);
      } catch (const Error& e) {
        throw Error(spec_.path + ": dataset.black_frames: " + e.what());
      }
    }
    if (dataset_->size() == 0) throw Error(dataset_->describe() + ": no frames in the selected range");
    dataset_record_.description = dataset_->describe();
    if (dopt.type == "kitti_odometry") {
      dataset_record_.kitti_root = dopt.root;
      dataset_record_.kitti_sequence = dopt.sequence;
    }
  }

  void createPlugins() {
    beslam_create_info base{};
    base.struct_size = sizeof(base);
    base.host = log_.host();
    const datasets::Camera& camera = dataset_->camera();
    base.camera.struct_size = sizeof(beslam_camera);
    base.camera.width = camera.width;
    base.camera.height = camera.height;
    base.camera.fx = camera.fx;
    base.camera.fy = camera.fy;
    base.camera.cx = camera.cx;
    base.camera.cy = camera.cy;
    if (const auto T = dataset_->T_cam_lidar()) {
      base.has_lidar_extrinsics = 1;
      base.T_cam_lidar = sdk::toPose(*T);
    }
    abs_out_dir_ = fs::absolute(out_dir_).string();
    base.output_dir = abs_out_dir_.c_str();
    base.camera_height =
        spec_.dataset.camera_height > 0 ? spec_.dataset.camera_height : dataset_->cameraHeight().value_or(0);
    camera_ = base.camera;
    summary_.output_dir = out_dir_;
    summary_.camera_height = base.camera_height;

    base_info_ = base;
    auto make = [&](const char* name, auto& instance) {
      instance = makeInstance<typename std::decay_t<decltype(instance)>::element_type>(name);
    };
    if (!spec_.slots.at("backend").plugin) throwAt(spec_.path, "backend: no plugin resolved");
    make("detector", detector_);
    make("motion_checker", motion_);
    make("mask_generator", masker_);
    make("reconstructor", reconstructor_);
    make("backend", backend_);
    record_.has_reconstructor = reconstructor_ != nullptr;
  }

  // A new instance of the plugin in slot `name` (null when the slot is empty), with the slot's settings.
  template <class Instance>
  std::unique_ptr<Instance> makeInstance(const char* name) {
    const SlotSpec& slot = spec_.slots.at(name);
    if (!slot.plugin) return nullptr;
    beslam_create_info info = base_info_;
    info.config = slot.config.values().data();
    info.config_count = static_cast<uint32_t>(slot.config.values().size());
    return std::make_unique<Instance>(*slot.plugin, info, log_);
  }

  // The stages that may run ahead on the producer thread: load, detect, (see execute) mask, and the
  // backend's prepare (ABI 1.4: its mask-independent work on the frame, which a backend makes safe against
  // its other calls). They touch only the frame, the dataset, the detector and the mask generator, never
  // the summary.
  void prepare(size_t i, FrameState& f) {
    load(i, f);
    detect(f);
    if (mask_ahead_) mask(f);
    if (backend_ahead_) {
      StageTimer timer(f.timing, "backend_prepare");
      backend_->prepare(f.view);
    }
  }

  // load: the frame from the dataset, and its ABI view.
  void load(size_t i, FrameState& f) {
    StageTimer timer(f.timing, "load");
    f.position = i;
    f.frame = dataset_->load(i);
    f.timing.index = f.frame.index;
    f.view = frameView(f.frame);
  }

  // predict: the backend's T_world_cam guess, asked only when the motion checker will use it. A pose in
  // an unknown unit would make parked cars seem to move (and cars keeping pace with the ego seem parked),
  // so the checker gets none until the backend's world is metric.
  void predict(FrameState& f) {
    if (!motion_ || !world_metric_) return;
    StageTimer timer(f.timing, "predict");
    f.T_world_cam_predicted = backend_->predictPose(f.view);
  }

  // detect: boxes, checked for NaN/inf before anything else sees them.
  void detect(FrameState& f) {
    if (!detector_) return;
    StageTimer timer(f.timing, "detector");
    f.boxes = detector_->detect(f.view);
    checkBoxes(f.boxes, detector_->plugin(), f.frame);
  }

  // frames.csv: the finished frame's row (what it tracked and what it saw), appended at once.
  void journalFrame(const FrameState& f) {
    detail::FrameJournalRow row;
    row.index = f.frame.index;
    row.timestamp = f.frame.timestamp;
    row.state = f.tracked.result.state;
    row.keyframe = f.tracked.result.is_keyframe != 0;
    row.tracked_points = f.tracked.result.tracked_points;
    row.metric = f.tracked.worldIsMetric();
    row.masked = f.mask_marked;
    for (const auto& [name, value] : f.tracked.counters)
      if (name == "features") row.features = value;
    row.detections = static_cast<int64_t>(f.boxes.size());
    for (const beslam_box3d& b : f.boxes)
      ++(b.motion_state == BESLAM_MOTION_STATIC    ? row.detections_static
         : b.motion_state == BESLAM_MOTION_DYNAMIC ? row.detections_dynamic
                                                   : row.detections_unknown);
    journal_->addFrame(row);
  }

  // classify: each box's motion state.
  void classify(FrameState& f) {
    if (motion_) {
      StageTimer timer(f.timing, "motion_checker");
      if (!world_metric_ && spec_.run.motion_replay_frames > 0) {
        unposed_.push_back({f.frame, spec_.run.motion_replay_boxes ? f.boxes : std::vector<beslam_box3d>{}});
        if (unposed_.size() > static_cast<size_t>(spec_.run.motion_replay_frames)) unposed_.pop_front();
      }
      std::vector<int32_t> detected_ids;
      for (const beslam_box3d& b : f.boxes) detected_ids.push_back(b.track_id);
      motion_->classify(f.view, f.T_world_cam_predicted, f.boxes);
      checkBoxes(f.boxes, motion_->plugin(), f.frame);
      for (size_t i = 0; i < f.boxes.size(); ++i) {  // ids the checker made up (not the detector's) move on
        beslam_box3d& b = f.boxes[i];
        if (b.track_id >= 0 && b.track_id != detected_ids[i]) b.track_id += track_id_offset_;
        max_track_id_ = std::max(max_track_id_, b.track_id);
      }
    }
    for (const beslam_box3d& b : f.boxes)
      ++(b.motion_state == BESLAM_MOTION_STATIC    ? summary_.detections_static
         : b.motion_state == BESLAM_MOTION_DYNAMIC ? summary_.detections_dynamic
                                                   : summary_.detections_unknown);
  }

  // mask: the per-pixel labels the backend extracts features by.
  void mask(FrameState& f) {
    if (!masker_) return;
    StageTimer timer(f.timing, "mask_generator");
    f.mask = cv::Mat::zeros(camera_.height, camera_.width, CV_16UC1);
    beslam_mask_buffer buffer{reinterpret_cast<uint16_t*>(f.mask.data), f.mask.cols, f.mask.rows,
                              static_cast<int32_t>(f.mask.step[0]), 0};
    masker_->generate(f.view, f.boxes, buffer);
    f.mask_marked = cv::countNonZero(f.mask) > 0;
  }

  // track: the backend's pose for the frame, its stage times and counters; the world unit follows the
  // backend's latest word (a reset map is unknown again); the summary keeps the frame from which the
  // world stayed metric.
  void track(FrameState& f) {
    {
      StageTimer timer(f.timing, "backend");
      f.tracked = backend_->track(f.view, sdk::toView(f.mask, BESLAM_PIXEL_LABEL16), f.boxes);
    }
    for (const auto& [name, ms] : f.tracked.stage_ms) f.timing.stages.emplace_back("backend." + name, ms);
    if (f.tracked.result.state == BESLAM_TRACKING_OK) ++summary_.tracked_online;
    record_.frame_indices.push_back(f.frame.index);
    double loop_closed = 0, loop_correction = 0;
    for (const auto& [name, value] : f.tracked.counters) {
      record_.counter_sums[name] += value;
      if (name == "loop_closures") loop_closed = value;
      if (name == "loop_correction_m") loop_correction = value;
      if (name == "relocalisations" && value > 0) record_.relocalisation_frames.push_back(f.frame.index);
    }
    if (loop_closed > 0) record_.loop_closures.push_back({f.frame.index, loop_correction});
    // A world moved under a metric map (a loop correction, a change of scale): the checker's tracks follow it
    // (ABI 1.7), so the correction does not read as parked cars moving.
    if (const auto change = f.tracked.worldChange(); change && world_metric_ && f.tracked.worldIsMetric()) {
      ++summary_.world_moves;
      if (motion_) {
        StageTimer timer(f.timing, "motion_world_moved");
        motion_->worldMoved(change->S_new_old, change->scale);
      }
    }
    if (f.tracked.worldIsMetric() != world_metric_) {
      world_metric_ = f.tracked.worldIsMetric();
      summary_.metric_from_frame = world_metric_ ? f.frame.index : -1;
      // A world metric from the first frame the backend answered for needs no second look.
      if (world_metric_ && unknown_world_seen_) replayMotionChecker(f.timing);
      unposed_.clear();
    }
    unknown_world_seen_ = !world_metric_;
  }

  // The motion checker again, on the frames it saw without a pose, now with the backend's metric poses
  // (runner.hpp): a new instance takes over with their history (boxes at the final poses) or having watched
  // the poses the backend gave them online (poses alone). A backend that cannot give its trajectory between
  // frames leaves the checker as it is (a warning).
  void replayMotionChecker(detail::TimingRow& timing) {
    if (!motion_ || unposed_.empty()) return;
    StageTimer timer(timing, "motion_replay");
    std::map<int64_t, Eigen::Isometry3d> T_world_cam;
    try {
      const int32_t which = spec_.run.motion_replay_boxes ? BESLAM_TRAJECTORY_FINAL : BESLAM_TRAJECTORY_ONLINE;
      for (const registry::PoseEntry& p : backend_->trajectory(which)) T_world_cam[p.frame_index] = p.T_world_cam;
    } catch (const Error& e) {
      if (options_.log_level <= BESLAM_LOG_WARNING)
        std::cerr << "warning: the motion checker starts without history: " << e.what() << "\n";
      return;
    }
    auto fresh = makeInstance<registry::MotionCheckerInstance>("motion_checker");
    for (UnposedFrame& u : unposed_) {
      const auto pose = T_world_cam.find(u.frame.index);
      fresh->classify(frameView(u.frame),
                      pose == T_world_cam.end() ? std::nullopt : std::optional<Eigen::Isometry3d>(pose->second),
                      u.boxes);
    }
    motion_ = std::move(fresh);
    track_id_offset_ = max_track_id_ + 1;  // past every id given out so far
    summary_.motion_replayed_frames += static_cast<int64_t>(unposed_.size());
  }

  // reconstruct: objects on new keyframes, in metres only (nothing before the world is metric), with the
  // backend's keyframe poses as they are now; the landmarks go back to the backend.
  void reconstruct(FrameState& f) {
    if (!reconstructor_ || !f.tracked.result.is_keyframe || !world_metric_) return;
    StageTimer timer(f.timing, "reconstructor");
    beslam_keyframe kf{};
    kf.struct_size = sizeof(kf);
    kf.id = f.tracked.result.keyframe_id;
    kf.frame_index = f.frame.index;
    kf.timestamp = f.frame.timestamp;
    kf.T_world_cam = f.tracked.result.T_world_cam;
    kf.world_scale = BESLAM_WORLD_SCALE_METRIC;
    kf.points = f.tracked.keyframe_points.empty() ? nullptr : f.tracked.keyframe_points.data();
    kf.point_count = static_cast<uint32_t>(f.tracked.keyframe_points.size());
    kf.point_size = sizeof(beslam_keyframe_point);
    // The backend's keyframes as they are now, so what the reconstructor keeps follows the map; the new
    // keyframe's own pose is its pose among them (its local BA may already have moved it).
    std::vector<beslam_trajectory_entry> keyframe_poses;
    keyframe_poses_given_.clear();
    for (const registry::PoseEntry& p : backend_->trajectory(BESLAM_TRAJECTORY_KEYFRAMES)) {
      keyframe_poses.push_back({p.frame_index, p.timestamp, sdk::toPose(p.T_world_cam)});
      keyframe_poses_given_[p.frame_index] = p.T_world_cam;
      if (p.frame_index == f.frame.index) kf.T_world_cam = keyframe_poses.back().T_world_cam;
    }
    kf.keyframe_poses = keyframe_poses.empty() ? nullptr : keyframe_poses.data();
    kf.keyframe_pose_count = static_cast<uint32_t>(keyframe_poses.size());
    kf.keyframe_pose_size = sizeof(beslam_trajectory_entry);
    const registry::Landmarks landmarks =
        reconstructor_->reconstruct(kf, f.view, f.boxes, sdk::toView(f.mask, BESLAM_PIXEL_LABEL16));
    detail::applyLandmarkUpdates(record_.objects, landmarks);
    // The landmarks are in the world the call was given: the keyframe's pose there is their anchor's.
    detail::anchorLandmarkUpdates(record_.anchors, landmarks, {f.frame.index, formats::toIsometry(kf.T_world_cam)});
    if (!landmarks.empty()) backend_->addLandmarks(landmarks);
  }

  // write: the per-frame outputs (objects.txt rows, masks/NNNNNN.png, samples/NNNNNN.jpg) and what the
  // static map needs (keyframes' scans, boxes not called static); everything else at the end.
  void write(FrameState& f) {
    StageTimer timer(f.timing, "write");
    if (detector_)
      for (const beslam_box3d& b : f.boxes) record_.object_rows.push_back(formatObjectRow(f.frame.index, b, camera_));
    if (spec_.output.masks) {
      const std::string path =
          (fs::path(out_dir_) / "masks" / (std::to_string(1000000 + f.frame.index).substr(1) + ".png")).string();
      std::vector<uchar> png;
      const cv::Mat labels = f.mask.empty() ? cv::Mat::zeros(camera_.height, camera_.width, CV_16UC1) : f.mask;
      if (!cv::imencode(".png", labels, png)) throwAt(path, "cannot encode mask");
      writeFileAtomic(path, std::string(png.begin(), png.end()));
    }
    if (sample_positions_.count(f.position)) writeSample(f);
    if (static_map_) {
      static_map_->addBoxes(f.frame.index, f.boxes);
      const auto T_cam_lidar = dataset_->T_cam_lidar();
      if (f.tracked.result.is_keyframe && T_cam_lidar && !f.frame.lidar_xyzi.empty())
        static_map_->addScan(f.frame.index, f.frame.lidar_xyzi.data(), f.frame.lidar_xyzi.size() / 4, 4 * sizeof(float),
                             *T_cam_lidar, f.boxes);
    }
  }

  // A sample frame is cosmetic: a frame without an image (a dataset of detections and poses only) has none,
  // and a failure to draw or write one is a warning, never the end of the run.
  void writeSample(const FrameState& f) {
    const cv::Mat& image = f.frame.color.empty() ? f.frame.gray : f.frame.color;
    const std::string path =
        (fs::path(out_dir_) / "samples" / (std::to_string(1000000 + f.frame.index).substr(1) + ".jpg")).string();
    std::string problem;
    if (image.empty()) {
      problem = "frame " + std::to_string(f.frame.index) + " has no image (the dataset has none)";
    } else {
      try {  // samples/ is made with the first sample (a dataset without images gets none)
        makeDirectories((fs::path(out_dir_) / "samples").string());
        detail::writeSampleFrame(path, detail::drawSampleFrame(image, f.mask, f.tracked.keypoints, f.boxes, camera_));
      } catch (const std::exception& e) {
        problem = e.what();
      }
    }
    if (!problem.empty() && !sample_warned_ && options_.log_level <= BESLAM_LOG_WARNING) {
      std::cerr << "warning: sample frame skipped: " << problem << " (further sample frames are skipped quietly)\n";
      sample_warned_ = true;
    }
  }

  const PipelineSpec& spec_;
  const RunOptions& options_;
  registry::HostLog log_;
  std::string out_dir_, abs_out_dir_;
  std::unique_ptr<detail::OutputLock> lock_;     // held for the run's whole life
  std::unique_ptr<detail::RunJournal> journal_;  // the tracked frames' poses and frames.csv, as they finish
  bool sample_warned_ = false;
  std::unique_ptr<datasets::Dataset> dataset_;
  detail::DatasetRecord dataset_record_;
  beslam_camera camera_{};
  std::unique_ptr<registry::DetectorInstance> detector_;
  std::unique_ptr<registry::MotionCheckerInstance> motion_;
  std::unique_ptr<registry::MaskGeneratorInstance> masker_;
  std::unique_ptr<registry::ReconstructorInstance> reconstructor_;
  std::map<int64_t, Eigen::Isometry3d> keyframe_poses_given_;  // to the reconstructor's last call, by frame
  std::unique_ptr<registry::BackendInstance> backend_;
  beslam_create_info base_info_{};    // what every instance is created with, before its slot's settings
  bool world_metric_ = false;         // the backend's world unit, as its last track() said (data.h)
  std::deque<UnposedFrame> unposed_;  // the latest frames classified without a pose (motion_replay_frames)
  bool unknown_world_seen_ = false;   // the backend's last track() said its world was not metric
  int32_t track_id_offset_ = 0;       // added to the track ids the current motion checker makes up
  int32_t max_track_id_ = -1;         // the largest track id given out
  bool mask_ahead_ = false;           // the mask is made on the producer thread (no motion checker)
  bool backend_ahead_ = false;        // the backend prepares each frame on the producer thread (ABI 1.4)
  std::set<size_t> sample_positions_;
  std::unique_ptr<static_map::StaticMapBuilder> static_map_;  // with output.octomap
  detail::RunRecord record_;
  RunSummary summary_;
};

}  // namespace

RunSummary run(const PipelineSpec& spec, const RunOptions& options) { return Run(spec, options).execute(); }

}  // namespace beslam::pipeline
