// The per-frame runner. Each frame passes through named stages, in this order, data flowing one way:
//   load -> predict -> detect -> classify -> mask -> track -> reconstruct -> write
// load reads the dataset frame; predict asks the backend for T_world_cam (only when a motion checker
// will use it, and only once the backend's world is metric); detect runs the detector and rejects
// NaN/inf boxes; classify gives each box a motion state; mask makes the per-pixel labels; track runs the
// backend; reconstruct (on metric keyframes) gives object landmarks back to the backend; write keeps the
// per-frame outputs. Every stage's wall time goes to timing.csv (docs/architecture.md has the diagram).
// At the end the run writes, each file atomically: trajectory.kitti / trajectory.tum (final poses),
// trajectory_online.tum, keyframes.tum, pipeline.resolved.yaml, timing.csv, summary.json, objects.txt
// (with a detector), masks/NNNNNN.png (with output.masks), map_points.ply (when the backend has a map).
// Frames the backend did not track are absent from the trajectories and listed in summary.json. On an
// error nothing partial replaces an earlier run's files. When options.stop_requested says so after a
// frame (SIGINT/SIGTERM in the CLI), the loop ends there and the outputs of the frames done are written,
// with summary.json "interrupted": true.
// The motion checker's history (spec.run.motion_replay_frames > 0; off by default, docs/motion.md): until the backend's
// world is metric the checker gets no pose, so it cannot tell parked from moving. The runner keeps the frames it saw so
// (at most motion_replay_frames, the latest) with their boxes as detected; on the frame the world turns metric it asks
// the backend for its trajectory (now in metres), starts a new checker instance with the same settings and runs it over
// those frames with their poses, then goes on with it. The states of the frames already processed are not changed;
// later frames are decided with the history. With spec.run.motion_replay_boxes false (`motion_replay: poses`) the
// runner keeps no boxes and the new instance gets the poses the backend gave those frames when it tracked them (its
// online trajectory, now in metres) and no boxes: it has watched the backend's poses, so it knows how much they
// jitter from the first metric frame on, and no car is measured in the young map's unit. The track ids the new instance
// makes up (not the detector's own, passed through) are moved past every id given out before, so such an id never names
// two objects. Scheduling (spec.run.prefetch > 0, the default): a producer thread loads the next frames and runs the
// detector on them (and the mask generator, when no motion checker needs the backend's pose first) while the backend
// works on the current one; at most `prefetch` frames wait. Each plugin is still called from one thread at a time,
// frame after frame in order, with the same inputs as in the strictly sequential loop (prefetch 0), so the results are
// the same; an interrupted run may have loaded and detected up to `prefetch` frames past the last one processed, which
// nothing else sees.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "beslam/pipeline/spec.hpp"

namespace beslam::pipeline {

struct RunOptions {
  std::string output_dir;  // overrides spec.output.dir when not empty
  bool progress = false;   // a progress line on stderr
  int32_t log_level = BESLAM_LOG_WARNING;
  // Asked after every frame: true ends the loop there (the outputs of the frames done are written).
  std::function<bool()> stop_requested;
  std::function<std::string()> stop_reason;  // e.g. "SIGTERM", for summary.json
  std::function<void(int64_t)> after_frame;  // called with each finished frame's index
  // A folder holding a previous run's outputs (summary.json, a trajectory) is refused unless this is set;
  // then that run's own files are removed first (nothing else in the folder).
  bool overwrite = false;
};

struct RunSummary {
  std::string output_dir;
  int64_t frames = 0;        // frames processed (all of the range unless interrupted)
  int64_t last_frame = -1;   // index of the last frame processed
  bool interrupted = false;  // the loop ended early on options.stop_requested
  std::string interrupted_by;
  int64_t tracked = 0;         // frames in the backend's final trajectory
  int64_t tracked_online = 0;  // frames the backend reported OK when it tracked them
  int64_t keyframes = 0;
  std::vector<int64_t> untracked;  // frame indices absent from the final trajectory
  bool has_ape = false;
  double ape_trans_rmse = 0;  // metres, with spec.evaluation.alignment
  double rpe_trans_rmse = 0;
  double ape_alignment_scale = 1;
  std::string evaluation_error;                // why APE could not be computed, when it could not
  double ape_sim3_rmse = 0, ape_se3_rmse = 0;  // both alignments, whatever spec.evaluation.alignment says
  double median_frame_ms = 0;
  double fps = 0;          // frames processed per second of the frame loop's wall time (not the setup, not the writing)
  double peak_rss_mb = 0;  // the process's peak resident memory when the outputs were written (MiB)
  // The world unit: the first frame the backend said its world was in metres (-1: never).
  int64_t metric_from_frame = -1;
  int64_t motion_replayed_frames = 0;  // frames the motion checker was run on again when the world turned metric
  int64_t world_moves = 0;             // times the backend moved its metric world (ABI 1.7), handed to the checker
  double camera_height = 0;            // the rig value handed to the plugins (0: unknown)
  // Detections after the motion checker, by motion state; frames whose mask marks any pixel.
  int64_t detections_static = 0, detections_dynamic = 0, detections_unknown = 0;
  int64_t frames_with_masks = 0;
  // Sums of the backend's per-frame counters ("features_static", "tracked_static", ...).
  std::vector<std::pair<std::string, double>> backend_counters;
  // The frames of the backend's events (its "loop_closures" and "relocalisations" counters above 0), with
  // the correction a loop closure applied (its "loop_correction_m", metres or map units).
  struct LoopClosure {
    int64_t frame = 0;
    double correction = 0;
  };
  std::vector<LoopClosure> loop_closures;
  std::vector<int64_t> relocalisation_frames;
  int64_t map_points = 0, map_points_static = 0;  // final map; on static objects (trusted)
  // Objects the reconstructor left at the end (objects.json) and how many have a mesh; -1: no reconstructor.
  int64_t objects_reconstructed = -1, objects_with_mesh = 0;
  // How the run ended, as summary.json says: "completed", "interrupted" or "failed: <reason>".
  std::string status;
};

// Runs a loaded and resolved pipeline (resolvePlugins). Throws beslam::Error (naming the file or plugin)
// on failure. The output folder is locked for the run (a second run into it fails at once). Every tracked
// frame's pose is appended to trajectory.tum and trajectory.kitti as the frame finishes, so a run that
// fails or is killed keeps them; a completed run replaces both with the backend's final trajectory. A
// run that fails after its first frame writes summary.json with status "failed: <reason>"; one that
// tracks fewer than output.min_tracked_share of its frames writes every output, then throws.
RunSummary run(const PipelineSpec& spec, const RunOptions& options);

}  // namespace beslam::pipeline
