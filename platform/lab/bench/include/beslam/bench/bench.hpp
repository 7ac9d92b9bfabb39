// `beslam bench`: an ablation matrix of pipelines x sequences x seeds, one ordinary `beslam run` a cell.
//
// Contract:
// - loadMatrix() reads a matrix file (docs/benchmarks.md) and validates all of it before anything runs;
//   any problem is one beslam::Error "MATRIX.yaml:LINE: problem". Relative paths resolve against the
//   matrix file's folder. Every pipeline file is loaded with its cell's --set overrides, so a bad key or
//   override is reported here and not half-way through the bench.
// - Cells are ordered seed, pipeline, sequence (outermost first): a partial bench still compares every
//   pipeline, and the first parallel cells render different synthetic sequences.
// - A cell's folder is OUT/runs/<pipeline>/<sequence>/seed<N>; it is finished when its summary.json parses
//   as a run summary not marked interrupted. Finished cells are skipped; the child's output goes to the folder's
//   beslam.log.
// - OUT/bench.json (written before any cell starts) freezes the cell list and the command of each cell, so
//   `--cell K OUT`, `--merge OUT` and the emitted Slurm script need only the folder.
// - A pipeline may ask for scoring steps (`score: [motion, objects, static_map]`): once its cells are
//   finished, each is scored as `beslam eval-motion|eval-objects|eval-static-map --run CELL` would, into
//   CELL/eval_<step>.json (scored again only when the run is newer than that file). The steps need the
//   truth of a synthetic sequence; a step that fails is one error naming the cell and the step.
// - Tables are computed from finished cells only (medians over seeds, even counts: mean of the middle
//   two; min and max) and written atomically: OUT/tables.md, OUT/tables.json, OUT/table1.csv,
//   OUT/table3.csv, OUT/objects.csv, and with scoring steps OUT/motion.csv, OUT/reconstruction.csv,
//   OUT/static_map.csv.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

namespace beslam::bench {

struct SequenceEntry {
  std::string label;
  std::vector<std::string> sets;  // --set overrides (dataset.sequence=..., dataset.root=<absolute>, ...)
};

struct PipelineEntry {
  std::string label;
  std::string file;  // absolute
  std::vector<std::string> sets;
  std::vector<std::string> sequences;  // labels; empty = every sequence
  std::vector<std::string> score;      // scoring steps: motion, objects, static_map (kScoreSteps)
};

// The scoring steps a pipeline may ask for, each the `beslam eval-<step>` command of the same name.
inline const std::vector<std::string> kScoreSteps = {"motion", "objects", "static_map"};

struct Matrix {
  std::string path;  // the matrix file as given
  std::string name;
  std::string seed_key = "backend.seed";
  std::vector<int64_t> seeds;
  std::vector<SequenceEntry> sequences;
  std::vector<PipelineEntry> pipelines;
};

struct Cell {
  int index = 0;
  std::string pipeline, sequence;
  int64_t seed = 0;
  std::string dir;                 // relative to the bench folder
  std::vector<std::string> args;   // arguments after the binary: run FILE --out DIR --quiet --set ...
  std::vector<std::string> score;  // the pipeline's scoring steps
};

Matrix loadMatrix(const std::string& path);
std::vector<Cell> makeCells(const Matrix& matrix, const std::string& out_dir);

// True when DIR/summary.json parses as a run summary of a run that was not interrupted.
bool cellFinished(const std::string& run_dir);

// Median (mean of the two middle values for an even count), min, max, count of the finite values.
struct Stat {
  double median = 0, min = 0, max = 0;
  int n = 0;
};
std::optional<Stat> stat(std::vector<double> values);

// Runs the scoring steps of every finished cell whose scores are missing or older than its run (reads
// OUT/bench.json). Throws beslam::Error naming the cell and the step when one fails.
void scoreCells(const std::string& out_dir);

// Tables from the finished cells of a bench folder (reads OUT/bench.json); returns the JSON written.
nlohmann::json writeTables(const std::string& out_dir);

// `beslam bench ...`; returns the exit status.
int runBenchCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace beslam::bench
