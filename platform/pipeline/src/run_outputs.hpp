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

// Writes every end-of-run file into `out_dir` and completes `summary` (frames, tracked, keyframes,
// map points, APE); static_map.bt too when `static_map` is given. Throws beslam::Error naming the file
// on a write failure.
void writeRunOutputs(const PipelineSpec& spec, const std::string& out_dir, const DatasetRecord& dataset_record,
                     datasets::Dataset& dataset, registry::BackendInstance& backend, const RunRecord& record,
                     static_map::StaticMapBuilder* static_map, RunSummary& summary);

}  // namespace beslam::pipeline::detail
