// The per-frame runner: dataset -> detector -> motion checker -> mask generator -> backend
// (-> reconstructor on new keyframes -> landmarks back to the backend).
//
// For each frame the backend first offers a predicted T_world_cam, which the motion checker uses to
// place boxes in the world frame; boxes from the detector are checked for NaN/inf before anything else
// sees them. Every stage's wall time is recorded. At the end the run writes, each file atomically:
// trajectory.kitti / trajectory.tum (final poses), trajectory_online.tum, keyframes.tum,
// pipeline.resolved.yaml, timing.csv, summary.json, objects.txt (with a detector), masks/NNNNNN.png
// (with output.masks), map_points.ply (when the backend has a map). Frames the backend did not track
// are absent from the trajectories and listed in summary.json. On an error nothing partial replaces
// an earlier run's files: per-frame files go to their own names, the rest is written at the end.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "beslam/pipeline/spec.hpp"

namespace beslam::pipeline {

struct RunOptions {
  std::string output_dir;             // overrides spec.output.dir when not empty
  bool progress = false;              // a progress line on stderr
  int32_t log_level = BESLAM_LOG_WARNING;
};

struct RunSummary {
  std::string output_dir;
  int64_t frames = 0;
  int64_t tracked = 0;                // frames in the backend's final trajectory
  int64_t tracked_online = 0;         // frames the backend reported OK when it tracked them
  int64_t keyframes = 0;
  std::vector<int64_t> untracked;     // frame indices absent from the final trajectory
  bool has_ape = false;
  double ape_trans_rmse = 0;          // metres, with spec.evaluation.alignment
  double rpe_trans_rmse = 0;
  double ape_alignment_scale = 1;
  std::string evaluation_error;       // why APE could not be computed, when it could not
  double ape_sim3_rmse = 0, ape_se3_rmse = 0;  // both alignments, whatever spec.evaluation.alignment says
  double median_frame_ms = 0;
  // The world unit: the first frame the backend said its world was in metres (-1: never).
  int64_t metric_from_frame = -1;
  double camera_height = 0;           // the rig value handed to the plugins (0: unknown)
  // Detections after the motion checker, by motion state; frames whose mask marks any pixel.
  int64_t detections_static = 0, detections_dynamic = 0, detections_unknown = 0;
  int64_t frames_with_masks = 0;
  // Sums of the backend's per-frame counters ("features_static", "tracked_static", ...).
  std::vector<std::pair<std::string, double>> backend_counters;
  int64_t map_points = 0, map_points_static = 0;  // final map; on static objects (trusted)
};

// Runs a loaded and resolved pipeline. Throws beslam::Error (naming the file or plugin) on failure.
RunSummary run(const PipelineSpec& spec, const registry::Registry& registry, const RunOptions& options);

}  // namespace beslam::pipeline
