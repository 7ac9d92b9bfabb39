// HTML reports of runs: a self-contained folder (index.html, lib/, data/, samples/) that opens offline.
//
// Contract:
// - writeRunReport(RUN, OUT) reads what `beslam run` wrote in RUN (summary.json required; trajectory.tum,
//   timing.csv, keyframes.tum, map_points.ply, objects.txt, samples/*.png|jpg where present) and the ground
//   truth the summary names (dataset_path: KITTI layout, poses/NN.txt + times.txt) and writes OUT/index.html
//   with per run: top view of the trajectory against the aligned ground truth, APE over time, scale over
//   time, per-stage timing, static/dynamic counts, sample frames, and a 3D map viewer. A timing.csv whose
//   header does not start with 'frame' or whose row has another number of fields is an error naming the
//   file and line.
// - writeBenchReport(DIR) does the same for every finished cell of a bench folder (DIR/bench.json),
//   with the tables of DIR/tables.json, into DIR/report/.
// - The JavaScript libraries (three.js r111 + OrbitControls, Chart.js 3) are copied from Debian's
//   libjs-three and libjs-chart.js (/usr/share/javascript, or $BESLAM_JS_DIR); a missing one is an error
//   naming the file and the package. Every file is written atomically.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace beslam::report {

// Returns what the report cannot show, one line each naming the file (a missing trajectory.tum or
// timing.csv, a run whose summary says it did not complete); beslam report prints them as warnings.
std::vector<std::string> writeRunReport(const std::string& run_dir, const std::string& out_dir);
void writeBenchReport(const std::string& bench_dir);

// `beslam report RUN_DIR [--out DIR]`; returns the exit status.
int runReportCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace beslam::report
