// What a run writes at its end (internal to the runner): the trajectories, map_points.ply, objects.txt,
// objects.json with objects/ and map.ply (with a reconstructor, object_outputs.hpp),
// pipeline.resolved.yaml, timing.csv and summary.json, each atomically. The frame loop collects a
// RunRecord; writeRunOutputs turns it into files and fills the RunSummary.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "beslam/datasets/dataset.hpp"
#include "beslam/pipeline/runner.hpp"
#include "beslam/registry/instance.hpp"
#include "beslam/static_map/static_map.hpp"
#include "object_outputs.hpp"

namespace beslam::pipeline::detail {

// One frame's stage times in the order they ran ("load", "detector", "backend.extract", ...).
struct TimingRow {
  int64_t index = 0;
  std::vector<std::pair<std::string, double>> stages;
  double rss_mb = 0;  // the process's resident memory at the frame's end (0: not measured)
};

// What the frame loop gathered; the backend's final state is read from the backend itself.
struct RunRecord {
  std::vector<TimingRow> timings;
  std::vector<double> frame_ms;
  std::vector<int64_t> frame_indices;    // frames that went through the backend, in order
  std::vector<std::string> object_rows;  // objects.txt
  std::map<std::string, double> counter_sums;
  std::vector<RunSummary::LoopClosure> loop_closures;  // frames of the backend's events (RunSummary)
  std::vector<int64_t> relocalisation_frames;
  ObjectMap objects;      // the reconstructor's latest landmark per object
  ObjectAnchors anchors;  // the keyframe each object was last fitted from
  bool has_reconstructor = false;
};

// Where the dataset came from, for summary.json (a synthetic sequence resolves to its cached folder).
struct DatasetRecord {
  std::string description;
  std::string kitti_root, kitti_sequence;  // set for KITTI-layout data: truth files live there
};

// The run's hold on its output folder: an exclusive flock on the folder itself (no file of its own),
// released when the process ends however it ends. Throws beslam::Error naming the folder when another
// run holds it.
class OutputLock {
 public:
  explicit OutputLock(const std::string& out_dir);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  int fd_ = -1;
};

// A folder holding a previous run's outputs (summary.json or a trajectory) is refused with one error,
// unless `overwrite`: then that run's own files (kRunFiles) and stale temporary files are removed, and
// nothing else in the folder.
void claimOutputFolder(const std::string& out_dir, bool overwrite);

// One finished frame as frames.csv records it.
struct FrameJournalRow {
  int64_t index = 0;  // the dataset's frame number
  double timestamp = 0;
  int32_t state = 0;  // BESLAM_TRACKING_*
  bool keyframe = false, metric = false, masked = false;
  int32_t tracked_points = 0;
  double features = -1;  // the backend's "features" counter; -1: it gave none
  int64_t detections = 0, detections_static = 0, detections_dynamic = 0, detections_unknown = 0;
};

// What survives a run that dies: written row by row as frames finish (each row one write(2) to a file
// opened with O_APPEND, so a killed process leaves whole rows):
//   trajectory.tum, trajectory.kitti  each tracked frame's pose; writeRunOutputs later replaces both with
//                                     the final trajectory;
//   frames.csv                        every frame: kFramesCsvHeader's columns (kept as it is at the end).
// A failed write is a warning (that file's journal stops; the run goes on).
class RunJournal {
 public:
  static constexpr const char* kFramesCsvHeader =
      "frame,timestamp,state,keyframe,tracked_points,features,detections,static,dynamic,unknown,masked,metric\n";
  explicit RunJournal(const std::string& out_dir);
  ~RunJournal();
  RunJournal(const RunJournal&) = delete;
  RunJournal& operator=(const RunJournal&) = delete;
  void addPose(double stamp, const Eigen::Isometry3d& T_world_cam);
  void addFrame(const FrameJournalRow& row);
  void close();

 private:
  struct File {
    std::string path;
    int fd = -1;
  };
  void append(File& file, const std::string& row);
  File tum_, kitti_, frames_;
};

// summary.json of a run that failed after it started: how far it got and why it ended.
void writeFailureSummary(const PipelineSpec& spec, const std::string& out_dir, const DatasetRecord& dataset_record,
                         const RunSummary& summary, int64_t frames, const std::string& reason);

// Writes every end-of-run file into `out_dir` and completes `summary` (frames, tracked, keyframes,
// map points, APE, status); static_map.bt too when `static_map` is given. The trajectories come first,
// then the map and the rest. A run not interrupted that tracks fewer than output.min_tracked_share of its
// frames gets status "failed: ..." (the caller throws). Throws beslam::Error naming the file on a write
// failure.
void writeRunOutputs(const PipelineSpec& spec, const std::string& out_dir, const DatasetRecord& dataset_record,
                     datasets::Dataset& dataset, registry::BackendInstance& backend, const RunRecord& record,
                     static_map::StaticMapBuilder* static_map, RunSummary& summary);

}  // namespace beslam::pipeline::detail
