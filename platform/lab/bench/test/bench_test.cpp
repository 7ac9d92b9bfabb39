// beslam bench: matrix validation (one error naming the file and the problem), the statistics, and one
// tiny real bench (2 pipelines x 1 short synthetic sequence x 2 seeds): tables equal to the runs' own
// summary.json, resume skips finished cells, the emitted Slurm script's tasks run locally + --merge.
#include "beslam/bench/bench.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <vector>

#include "beslam/common/error.hpp"
#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;
using beslam::bench::loadMatrix;
using nlohmann::json;

namespace {

using beslam::test::readText;

void write(const fs::path& p, const std::string& s) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << s;
}

struct Result {
  int code;
  std::string out, err;
};

Result shell(const std::string& cmd, const fs::path& dir) {
  const fs::path o = dir / "stdout.txt", e = dir / "stderr.txt";
  const int status = std::system((cmd + " > " + o.string() + " 2> " + e.string() + " < /dev/null").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, readText(o), readText(e)};
}

const std::string kBeslam = std::string(BESLAM_BINARY_DIR) + "/bin/beslam";
const std::string kAblation = std::string(BESLAM_SOURCE_DIR) + "/configs/ablation/";

fs::path tempDir(const std::string& name) {
  const fs::path d = fs::path(BESLAM_BINARY_DIR) / "test-bench" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string goodMatrix(const std::string& extra_pipeline = "") {
  return "name: t\nseeds: [1, 2]\nsequences:\n  - {label: ds, sequence: dynamic_street}\npipelines:\n"
         "  - {label: plain, file: " +
         kAblation + "synth_no_semantics.yaml}\n" + extra_pipeline;
}

// The error of loadMatrix on `text`, which must name the file (and line) and contain `problem`.
void expectError(const std::string& text, const std::string& problem, bool with_line = true) {
  const fs::path dir = tempDir("errors");
  const fs::path m = dir / "m.yaml";
  write(m, text);
  try {
    loadMatrix(m.string());
    FAIL() << "no error for: " << text;
  } catch (const beslam::Error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(m.string() + (with_line ? ":" : ""), 0), 0u) << msg;
    if (with_line) {
      EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(msg[m.string().size() + 1]))) << msg;
    }
    EXPECT_NE(msg.find(problem), std::string::npos) << msg;
  }
}

}  // namespace

TEST(BenchStat, MedianMinMaxOfFiniteValues) {
  const auto s = beslam::bench::stat({3.0, NAN, 1.0, 2.0});
  ASSERT_TRUE(s);
  EXPECT_EQ(s->n, 3);
  EXPECT_EQ(s->median, 2.0);
  EXPECT_EQ(s->min, 1.0);
  EXPECT_EQ(s->max, 3.0);
  const auto e = beslam::bench::stat({4.0, 1.0, 2.0, 10.0});
  EXPECT_EQ(e->median, 3.0);  // mean of the middle two
  EXPECT_FALSE(beslam::bench::stat({NAN}));
}

TEST(BenchMatrix, GoodMatrixMakesCellsSeedOutermost) {
  const fs::path dir = tempDir("good");
  write(dir / "m.yaml", goodMatrix("  - {label: masked, file: " + kAblation +
                                   "synth_mask_all_cars.yaml, set: [backend.features=1000]}\n"));
  const auto m = loadMatrix((dir / "m.yaml").string());
  const auto cells = beslam::bench::makeCells(m, dir.string());
  ASSERT_EQ(cells.size(), 4u);
  EXPECT_EQ(cells[0].dir, "runs/plain/ds/seed1");
  EXPECT_EQ(cells[1].dir, "runs/masked/ds/seed1");
  EXPECT_EQ(cells[3].dir, "runs/masked/ds/seed2");
  const auto& a = cells[3].args;
  EXPECT_NE(std::find(a.begin(), a.end(), "backend.features=1000"), a.end());
  EXPECT_NE(std::find(a.begin(), a.end(), "backend.seed=2"), a.end());
  EXPECT_NE(std::find(a.begin(), a.end(), "dataset.sequence=\"dynamic_street\""), a.end());
}

TEST(BenchMatrix, BadFilesGiveOneErrorNamingFileAndProblem) {
  expectError("seeds: [1]\nsequences: [{label: a, sequence: x}]\n", "pipelines: missing", false);
  expectError("name: t\nseeds: [1, 1]\n", "listed twice");
  expectError("seeds: [one]\n", "'one' is not an integer");
  expectError(goodMatrix() + "colour: red\n", "unknown key 'colour'");
  expectError(goodMatrix("  - {label: plain, file: " + kAblation + "synth_beslam.yaml}\n"), "'plain' is used twice");
  expectError(goodMatrix("  - {label: x, file: nowhere.yaml}\n"), "no such file");
  expectError(goodMatrix("  - {label: 'a/b', file: " + kAblation + "synth_beslam.yaml}\n"), "not a folder-safe name");
  expectError(goodMatrix("  - {label: x, file: " + kAblation + "synth_beslam.yaml, sequences: [nope]}\n"),
              "no sequence is labelled 'nope'");
  expectError(goodMatrix("  - {label: x, file: " + kAblation + "synth_beslam.yaml, set: [novalue]}\n"),
              "not key=value");
  // Problems inside a cell's pipeline (here an unknown plugin setting) are found before anything runs.
  expectError(goodMatrix("  - {label: x, file: " + kAblation + "synth_beslam.yaml, set: [backend.no_such_key=1]}\n"),
              "pipeline 'x' on sequence 'ds'");
  expectError("seeds: [1\n", "YAML syntax error");
  for (const auto& [score, problem] : std::vector<std::pair<std::string, std::string>>{
           {"[speed]", "score: unknown step 'speed' (known: motion, objects, static_map)"},
           {"[motion, motion]", "'motion' is listed twice"},
           {"motion", "expected a list of scoring steps"}})
    expectError(goodMatrix("  - {label: x, file: " + kAblation + "synth_beslam.yaml, score: " + score + "}\n"),
                problem);
}

TEST(BenchCommand, BadMatrixIsOneLineAndExitOne) {
  const fs::path dir = tempDir("cli");
  write(dir / "m.yaml", goodMatrix() + "colour: red\n");
  const Result r = shell(kBeslam + " bench " + (dir / "m.yaml").string() + " --out " + (dir / "out").string(), dir);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind("beslam: error: " + (dir / "m.yaml").string() + ":", 0), 0u) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "bench.json"));
  EXPECT_EQ(shell(kBeslam + " bench --jobs 0 x.yaml", dir).code, 2);
}

// --seeds replaces the matrix's seeds (a figure measured on other seeds is one flag away); a bad list is a
// usage error naming the item.
TEST(BenchCommand, SeedsFlagReplacesTheMatrixSeeds) {
  const fs::path dir = tempDir("seeds");
  write(dir / "m.yaml", goodMatrix());
  const Result r = shell(
      kBeslam + " bench " + (dir / "m.yaml").string() + " --seeds 7,31 --emit slurm --out " + (dir / "out").string(),
      dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const json bench = json::parse(readText(dir / "out/bench.json"));
  std::set<int64_t> seeds;
  for (const auto& c : bench["cells"]) seeds.insert(c["seed"].get<int64_t>());
  EXPECT_EQ(seeds, (std::set<int64_t>{7, 31}));
  for (const std::string bad : {"7,x", "7,7", "", "3.5"}) {
    const Result e =
        shell(kBeslam + " bench " + (dir / "m.yaml").string() + " --seeds '" + bad + "' --emit slurm", dir);
    EXPECT_EQ(e.code, 2) << bad;
    EXPECT_NE(e.err.find("--seeds"), std::string::npos) << e.err;
  }
}

namespace {

double at(const json& j, std::initializer_list<const char*> path) {
  const json* p = &j;
  for (const char* k : path) p = &(*p)[k];
  return p->get<double>();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : (v[v.size() / 2 - 1] + v[v.size() / 2]) / 2;
}

// Every Table I / objects figure of tables.json equals the median / min / max of the runs' own summaries.
void expectTablesMatchSummaries(const fs::path& out, int cells) {
  const json t = json::parse(readText(out / "tables.json"));
  ASSERT_EQ(t["finished"], cells);
  const json bench = json::parse(readText(out / "bench.json"));
  int rows = 0;
  for (const auto& row : t["table1"]) {
    std::vector<json> sums;
    for (const auto& c : bench["cells"])
      if (c["pipeline"] == row["pipeline"] && c["sequence"] == row["sequence"])
        sums.push_back(json::parse(readText(out / c["dir"].get<std::string>() / "summary.json")));
    ASSERT_EQ(row["runs"], sums.size());
    auto check = [&](const json& s, std::initializer_list<const char*> path) {
      std::vector<double> v;
      for (const auto& j : sums) v.push_back(at(j, path));
      ASSERT_FALSE(s.is_null());
      EXPECT_EQ(s["median"].get<double>(), median(v));
      EXPECT_EQ(s["min"].get<double>(), *std::min_element(v.begin(), v.end()));
      EXPECT_EQ(s["max"].get<double>(), *std::max_element(v.begin(), v.end()));
    };
    check(row["ape_sim3_rmse"], {"ape", "sim3_rmse"});
    check(row["ape_se3_rmse"], {"ape", "se3_rmse"});
    check(row["sim3_scale"], {"ape", "sim3_scale"});
    check(row["rpe_trans_rmse"], {"evaluation", "rpe", "trans", "rmse"});
    check(row["tracked"], {"tracked"});
    for (const auto& o : t["objects"])
      if (o["pipeline"] == row["pipeline"] && o["sequence"] == row["sequence"]) {
        check(o["static"], {"detections", "static"});
        check(o["dynamic"], {"detections", "dynamic"});
        check(o["unknown"], {"detections", "unknown"});
        check(o["map_points_static"], {"map_points", "on_static_objects"});
      }
    ++rows;
  }
  EXPECT_EQ(rows, 2);
  // The CSV carries the same numbers at full precision.
  const std::string csv = readText(out / "table1.csv");
  const std::string first = t["table1"][0]["ape_sim3_rmse"]["median"].dump();
  EXPECT_NE(csv.find("," + first + ","), std::string::npos) << csv;
  EXPECT_EQ(std::stod(first), t["table1"][0]["ape_sim3_rmse"]["median"].get<double>());
  // Table III: semantic time only where the pipeline has semantic stages.
  for (const auto& r : t["table3"]) {
    EXPECT_FALSE(r["tracking_ms"].is_null());
    EXPECT_EQ(r["semantic_ms"].is_null(), r["pipeline"] == "plain");
  }
}

// The motion table (scoring step `motion`): one row per scored pipeline, each figure the median / min / max
// of the cells' eval_motion.json; unscored pipelines have no row and no file.
void expectMotionTableMatchesScores(const fs::path& out, int runs) {
  const json t = json::parse(readText(out / "tables.json"));
  const json bench = json::parse(readText(out / "bench.json"));
  ASSERT_EQ(t["motion"].size(), 1u) << t["motion"].dump();
  const json& row = t["motion"][0];
  EXPECT_EQ(row["pipeline"], "beslam");
  EXPECT_EQ(row["runs"], runs);
  std::vector<double> f1, moving_static;
  for (const auto& c : bench["cells"]) {
    const fs::path score = out / c["dir"].get<std::string>() / "eval_motion.json";
    ASSERT_EQ(fs::exists(score), c["pipeline"] == "beslam") << score;
    if (!fs::exists(score)) continue;
    const json j = json::parse(readText(score));
    f1.push_back(j["f1_dynamic"].get<double>());
    moving_static.push_back(j["moving"].get<double>() > 0 ? j["moving_static"].get<double>() / j["moving"].get<double>()
                                                          : 0);
  }
  EXPECT_EQ(row["f1_dynamic"]["median"].get<double>(), median(f1));
  EXPECT_EQ(row["moving_called_static"]["max"].get<double>(),
            *std::max_element(moving_static.begin(), moving_static.end()));
  EXPECT_GT(row["f1_dynamic"]["median"].get<double>(), 0.5);  // the checker works on dynamic_street
  EXPECT_NE(readText(out / "tables.md").find("## Motion states"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "motion.csv"));
  EXPECT_FALSE(fs::exists(out / "reconstruction.csv"));
}

// A matrix of 60 synthetic dynamic_street frames (rendered once into the build tree's cache) with the
// given seeds and pipelines: "plain" (no semantics) and/or "beslam" (the full pipeline).
void writeTinyMatrix(const fs::path& file, const std::string& name, const std::string& seeds,
                     const std::vector<std::string>& pipelines) {
  const fs::path cache = fs::path(BESLAM_BINARY_DIR) / "test-bench-synth-cache";
  std::string yaml = "name: " + name + "\nseeds: " + seeds + "\nsequences:\n" +
                     "  - label: ds\n    sequence: dynamic_street\n    root: " + cache.string() + "\n" +
                     "    set: [\"dataset.synth_set=lidar.enabled=false,camera.colour=false,frames=60\"]\n" +
                     "pipelines:\n";
  for (const std::string& label : pipelines)
    yaml += "  - {label: " + label + ", file: " + kAblation +
            (label == "plain" ? "synth_no_semantics.yaml}\n" : "synth_beslam.yaml, score: [motion]}\n");
  write(file, yaml);
}

}  // namespace

TEST(BenchCommand, TinyBenchTablesResumeSlurmAndMerge) {
  const fs::path dir = tempDir("tiny");
  writeTinyMatrix(dir / "m.yaml", "tiny", "[1, 2]", {"plain", "beslam"});
  const fs::path out = dir / "out";
  Result r = shell(kBeslam + " bench " + (dir / "m.yaml").string() + " --out " + out.string() + " --jobs 2", dir);
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  EXPECT_NE(r.err.find("4 cells, 0 already finished, 4 to run"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("[4/4 cells]"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("## Table I"), std::string::npos);
  expectTablesMatchSummaries(out, 4);
  expectMotionTableMatchesScores(out, 2);
  for (const char* f :
       {"tables.md", "table1.csv", "table3.csv", "objects.csv", "report/index.html", "report/lib/three.min.js",
        "report/lib/OrbitControls.js", "report/lib/chart.min.js", "report/data/run_3.js"})
    EXPECT_TRUE(fs::exists(out / f)) << f;

  // Resume: nothing runs again.
  const auto stamp = fs::last_write_time(out / "runs/beslam/ds/seed2/summary.json");
  const auto score_stamp = fs::last_write_time(out / "runs/beslam/ds/seed2/eval_motion.json");
  r = shell(kBeslam + " bench " + (dir / "m.yaml").string() + " --out " + out.string() + " --jobs 2", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("4 already finished, 0 to run"), std::string::npos) << r.err;
  EXPECT_EQ(fs::last_write_time(out / "runs/beslam/ds/seed2/summary.json"), stamp);
  EXPECT_EQ(fs::last_write_time(out / "runs/beslam/ds/seed2/eval_motion.json"), score_stamp);  // not scored again
  {  // a scoring step that cannot run (no reconstructor, so no objects.json) is one error naming cell and step
    json bench = json::parse(readText(out / "bench.json"));
    bench["cells"][1]["score"] = {"objects"};
    std::ofstream(out / "bench.json") << bench.dump();
    r = shell(kBeslam + " bench --merge " + out.string(), dir);
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find("runs/beslam/ds/seed1: scoring step 'objects' failed: "), std::string::npos) << r.err;
    bench["cells"][1]["score"] = {"motion"};
    std::ofstream(out / "bench.json") << bench.dump();
  }

  // A broken summary is not a finished cell: --cell reruns it.
  {  // an interrupted run (SIGINT) writes a summary too: not finished
    json j = json::parse(readText(out / "runs/plain/ds/seed1/summary.json"));
    j["interrupted"] = true;
    std::ofstream(out / "runs/plain/ds/seed1/summary.json") << j.dump();
    EXPECT_FALSE(beslam::bench::cellFinished((out / "runs/plain/ds/seed1").string()));
  }
  std::ofstream(out / "runs/plain/ds/seed1/summary.json") << "{\"frames\": ";
  EXPECT_FALSE(beslam::bench::cellFinished((out / "runs/plain/ds/seed1").string()));
  r = shell(kBeslam + " bench --cell 0 " + out.string(), dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("finished in"), std::string::npos) << r.out;
  EXPECT_TRUE(beslam::bench::cellFinished((out / "runs/plain/ds/seed1").string()));
  EXPECT_EQ(shell(kBeslam + " bench --cell 9 " + out.string(), dir).code, 1);

  // Slurm: the emitted array script, each task run here with SLURM_ARRAY_TASK_ID, then --merge.
  const fs::path sl = dir / "slurm";
  r = shell(kBeslam + " bench " + (dir / "m.yaml").string() + " --out " + sl.string() + " --emit slurm", dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string script = readText(sl / "bench.sbatch");
  EXPECT_NE(script.find("#SBATCH --array=0-3"), std::string::npos) << script;
  EXPECT_FALSE(fs::exists(sl / "runs"));
  EXPECT_NE(shell("bash " + (sl / "bench.sbatch").string(), dir).code, 0);  // no task id: refuses
  for (int k = 0; k < 4; ++k) {
    r = shell("SLURM_ARRAY_TASK_ID=" + std::to_string(k) + " bash " + (sl / "bench.sbatch").string(), dir);
    ASSERT_EQ(r.code, 0) << r.err << r.out;
  }
  r = shell(kBeslam + " bench --merge " + sl.string(), dir);
  ASSERT_EQ(r.code, 0) << r.err;
  expectTablesMatchSummaries(sl, 4);
  EXPECT_TRUE(fs::exists(sl / "report/index.html"));
}

// A cell whose run was interrupted (SIGINT at frame 3, through the runner's real signal path) wrote a
// summary marked interrupted: the bench says the cell failed, and running it again reruns that cell.
TEST(BenchCommand, InterruptedCellIsRunAgain) {
  const fs::path dir = tempDir("interrupted");
  writeTinyMatrix(dir / "m.yaml", "interrupted", "[1]", {"plain"});
  const std::string bench = kBeslam + " bench " + (dir / "m.yaml").string() + " --out " + (dir / "out").string();
  Result r = shell("BESLAM_DEBUG_SIGNAL_AT=3:SIGINT " + bench, dir);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("FAILED runs/plain/ds/seed1 (exit 130"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("beslam: error: " + (dir / "out").string() + ": 1 of 1 cells failed"), std::string::npos)
      << r.err;
  const json s = json::parse(readText(dir / "out/runs/plain/ds/seed1/summary.json"));
  EXPECT_TRUE(s["interrupted"].get<bool>());
  EXPECT_EQ(json::parse(readText(dir / "out/tables.json"))["finished"], 0);
  r = shell(bench, dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("0 already finished, 1 to run"), std::string::npos) << r.err;
  EXPECT_EQ(json::parse(readText(dir / "out/tables.json"))["finished"], 1);
}

// Probes: a matrix name with line breaks ran `touch` when the emitted job script was submitted; a name
// like ../../../../tmp/escaped wrote bench.json and bench.sbatch outside the output folder. Names are
// one folder-safe name now, refused before anything is written.
TEST(BenchMatrix, HostileNamesAreRefused) {
  const std::string rest = goodMatrix().substr(std::string("name: t\n").size());
  expectError("name: \"x\\ntouch /tmp/INJECTED\\n#\"\n" + rest,
              "name: 'x?touch /tmp/INJECTED?#' is not a folder-safe name");
  expectError("name: ../../../../tmp/escaped\n" + rest, "name: '../../../../tmp/escaped' is not a folder-safe name");
  expectError("name: ..\n" + rest, "is not a folder-safe name");
  expectError("name: [a, b]\n" + rest, "name: expected a single value");

  const fs::path dir = tempDir("hostile_name");
  write(dir / "m.yaml", "name: ../../escaped\n" + rest);
  const Result r = shell("cd " + dir.string() + " && " + kBeslam + " bench m.yaml --emit slurm", dir);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_FALSE(fs::exists(dir.parent_path().parent_path() / "escaped"));
}

namespace {

std::vector<std::string> filesUnder(const fs::path& root) {
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

// The emitted script is run by bash with an output folder whose name is full of shell syntax: every
// value reaches beslam as one argument, nothing is executed, nothing is written outside the folder.
TEST(BenchCommand, EmittedScriptQuotesEverything) {
  const fs::path dir = tempDir("hostile_script");
  write(dir / "m.yaml", goodMatrix());
  const fs::path out = dir / "out $(touch INJECTED1) `touch INJECTED2` ;touch INJECTED3; 'q' $HOME *";
  const std::string quoted_out =
      "'" + std::string("out $(touch INJECTED1) `touch INJECTED2` ;touch INJECTED3; '\\''q'\\'' $HOME *") + "'";
  fs::create_directories(dir / "cwd");
  Result r = shell(
      "cd " + (dir / "cwd").string() + " && " + kBeslam + " bench ../m.yaml --emit slurm --out ../" + quoted_out, dir);
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path script = out / "bench.sbatch";
  ASSERT_TRUE(fs::exists(script)) << r.out;
  const auto before = filesUnder(dir);
  // A stub sbatch runs the script as one array task would; the task's cell does not exist (99), so beslam
  // answers with an error naming the folder it was given: intact, as one argument.
  write(dir / "bin" / "sbatch", "#!/bin/sh\nSLURM_ARRAY_TASK_ID=99 exec bash \"$1\"\n");
  fs::permissions(dir / "bin" / "sbatch", fs::perms::owner_all);
  r = shell("cd " + (dir / "cwd").string() + " && PATH=" + (dir / "bin").string() + ":$PATH sbatch ../" + quoted_out +
                "/bench.sbatch",
            dir);
  EXPECT_EQ(r.code, 1) << r.err << r.out;
  EXPECT_NE(r.err.find("beslam: error: " + (out / "bench.json").string() + ": no cell 99"), std::string::npos) << r.err;
  auto after = filesUnder(dir);
  after.erase(std::remove_if(after.begin(), after.end(),
                             [&](const std::string& f) {
                               return f == (dir / "stdout.txt").string() || f == (dir / "stderr.txt").string() ||
                                      f.rfind((dir / "bin").string(), 0) == 0;
                             }),
              after.end());
  std::vector<std::string> expected = before;
  expected.erase(std::remove_if(expected.begin(), expected.end(),
                                [&](const std::string& f) {
                                  return f == (dir / "stdout.txt").string() || f == (dir / "stderr.txt").string();
                                }),
                 expected.end());
  EXPECT_EQ(after, expected);  // the task wrote nothing anywhere
  for (const std::string& f : after) EXPECT_NE(fs::path(f).filename().string().rfind("INJECTED", 0), 0u) << f;
  for (const char* f : {"INJECTED1", "INJECTED2", "INJECTED3"}) EXPECT_FALSE(fs::exists(dir / "cwd" / f)) << f;
  const std::string text = readText(script);
  EXPECT_NE(text.find("#SBATCH --output=\"" + out.string() + "/slurm/%A_%a.out\""), std::string::npos) << text;

  // What no quoting can carry into a directive or a comment is refused: a line break in --out.
  r = shell(
      kBeslam + " bench " + (dir / "m.yaml").string() + " --emit slurm --out '" + dir.string() + "/a\ntouch INJECTED4'",
      dir);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("cannot be written into a job script"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "a\ntouch INJECTED4"));
}

// Every shipped matrix loads: its files exist, and each cell's pipeline resolves with its overrides.
TEST(BenchMatrix, ShippedMatricesLoad) {
  const fs::path root = fs::path(BESLAM_SOURCE_DIR) / "configs" / "bench";
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(root)) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    try {
      const auto m = loadMatrix(entry.path().string());
      EXPECT_FALSE(beslam::bench::makeCells(m, "out").empty());
      ++checked;
    } catch (const beslam::Error& e) {
      // The KITTI matrix needs the excerpts and the detector's model in ../shared beside the clone.
      const bool shared = fs::exists(std::string(BESLAM_SHARED_DATA) + "/kitti/odometry") &&
                          fs::exists(std::string(BESLAM_SHARED_MODELS) + "/yolo-fastest-1.1");
      if (entry.path().filename() == "kitti.yaml" && !shared) {
        std::cout << "kitti.yaml not checked: ../shared data or models absent (" << e.what() << ")\n";
        continue;
      }
      ADD_FAILURE() << e.what();
    }
  }
  EXPECT_GE(checked, 1);
}
