// `beslam bench`: run the cells (N at a time, each a child `beslam run`), print progress, write the tables
// and the report; or emit a Slurm job array, run one cell, merge finished cells.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "beslam/bench/bench.hpp"
#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/motion_score/motion_score.hpp"
#include "beslam/object_score/object_score.hpp"
#include "beslam/report/report.hpp"
#include "beslam/sdk/cli_args.hpp"
#include "beslam/static_map/score.hpp"

extern char** environ;
namespace fs = std::filesystem;
using nlohmann::json;

namespace beslam::bench {
namespace {

constexpr const char* kUsage =
    "usage: beslam bench MATRIX.yaml [--out DIR] [--jobs N] [--seeds A,B,...] [--emit slurm]\n"
    "       beslam bench --merge DIR\n"
    "       beslam bench --cell K DIR\n"
    "\n"
    "Runs every cell of an ablation matrix (pipelines x sequences x seeds; docs/benchmarks.md) as an\n"
    "ordinary `beslam run` into DIR/runs/<pipeline>/<sequence>/seed<N>, skipping finished cells, then writes\n"
    "DIR/tables.md, tables.json, the CSV tables and DIR/report/index.html; a pipeline's scoring steps\n"
    "(score: [motion, objects, static_map]) score its finished cells first, into CELL/eval_<step>.json.\n"
    "  --out DIR       bench folder (default out/bench/<matrix name>)\n"
    "  --jobs N        cells run at once (default 1)\n"
    "  --seeds A,B,... these backend seeds instead of the matrix's (its seed_key; integers, each once)\n"
    "  --emit slurm    write DIR/bench.json and DIR/bench.sbatch (one array task a cell) and run nothing\n"
    "  --merge DIR     tables and report from the finished cells of DIR\n"
    "  --cell K DIR    run cell K of DIR/bench.json (what each Slurm array task does)\n";

struct Usage : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// "42,1,2": whole numbers, each once.
std::vector<int64_t> seedList(const std::string& text) {
  std::vector<int64_t> seeds;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    int64_t v = 0;
    try {
      v = cli::integerInRange("--seeds", item, std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
    } catch (const std::invalid_argument& e) {
      throw Usage(e.what());
    }
    if (std::find(seeds.begin(), seeds.end(), v) != seeds.end()) throw Usage("--seeds: " + item + " is listed twice");
    seeds.push_back(v);
  }
  if (seeds.empty()) throw Usage("--seeds: expected a list such as 42,1,2");
  return seeds;
}

int cliInteger(const std::string& flag, const std::string& text, int lo, int hi) {
  try {
    return cli::integerInRange(flag, text, lo, hi);
  } catch (const std::invalid_argument& e) {
    throw Usage(e.what());
  }
}

std::string selfExe() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw Error("/proc/self/exe: cannot find the beslam binary: " + ec.message());
  return p.string();
}

std::string shellQuote(const std::string& s) {
  std::string o = "'";
  for (char c : s) o += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return o + "'";
}

// A path or name written into a line of the job script where no shell quoting applies (a comment, an
// #SBATCH directive: sbatch reads double quotes only). It may hold no line break or other control
// character, no double quote and no backslash.
std::string scriptSafe(const std::string& s, const std::string& what) {
  for (char c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f || c == '"' || c == '\\')
      throw Error(what + " '" + s.substr(0, 200) +
                  "' holds a control character, a double quote or a backslash: it cannot be written into a job "
                  "script (choose another folder)");
  return s;
}

std::string clock(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  std::ostringstream o;
  o << s / 60 << ":" << std::setw(2) << std::setfill('0') << s % 60;
  return o.str();
}

json describe(const Matrix& m, const std::vector<Cell>& cells, const std::string& binary) {
  json j = {{"name", m.name},
            {"matrix", fs::absolute(m.path).lexically_normal().string()},
            {"binary", binary},
            {"seeds", m.seeds},
            {"cells", json::array()}};
  for (const auto& c : cells) {
    json cell = {{"index", c.index}, {"pipeline", c.pipeline}, {"sequence", c.sequence},
                 {"seed", c.seed},   {"dir", c.dir},           {"args", c.args}};
    if (!c.score.empty()) cell["score"] = c.score;  // absent otherwise: older bench folders stay valid
    j["cells"].push_back(cell);
  }
  return j;
}

json readBench(const std::string& dir) {
  const std::string path = (fs::path(dir) / "bench.json").string();
  try {
    json j = json::parse(readFile(path));
    if (!j.contains("cells") || !j["cells"].is_array()) throwAt(path, "not a bench description: no 'cells' list");
    return j;
  } catch (const json::exception& e) {
    throwAt(path, std::string("not a bench description: ") + e.what());
  }
}

// Starts one cell as a child process; its stdout and stderr go to the cell folder's beslam.log.
pid_t startCell(const std::string& binary, const std::string& bench_dir, const json& cell) {
  const fs::path dir = fs::absolute(fs::path(bench_dir) / cell.at("dir").get<std::string>());
  makeDirectories(dir.string());
  std::vector<std::string> argv = {binary};
  for (const auto& a : cell.at("args")) argv.push_back(a.get<std::string>());
  // Only unfinished cells are started: what a failed or interrupted attempt left there is replaced.
  argv.insert(argv.end(), {"--out", dir.string(), "--overwrite"});
  std::vector<char*> cargv;
  for (auto& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  const std::string log = (dir / "beslam.log").string();
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, binary.c_str(), &fa, nullptr, cargv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throwAt(binary, std::string("cannot start a cell: ") + std::strerror(rc));
  return pid;
}

int exitCode(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status); }

// Runs the unfinished cells, `jobs` at a time. Returns the folders of the cells that failed.
std::vector<std::string> runCells(const json& bench, const std::string& dir, int jobs, std::ostream& err) {
  const std::string binary = selfExe();
  const auto& cells = bench["cells"];
  const int total = static_cast<int>(cells.size());
  std::vector<int> todo;
  int done = 0;
  for (int i = 0; i < total; ++i) {
    if (cellFinished((fs::path(dir) / cells[i]["dir"].get<std::string>()).string()))
      ++done;
    else
      todo.push_back(i);
  }
  const int skipped = done;
  const bool tty = isatty(STDERR_FILENO) && &err == &std::cerr;
  const auto t0 = std::chrono::steady_clock::now();
  auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  double ran_seconds = 0;
  int ran = 0;
  std::vector<std::string> failed;
  std::map<pid_t, std::pair<int, std::chrono::steady_clock::time_point>> running;
  err << "bench " << bench.value("name", "") << ": " << total << " cells, " << skipped << " already finished, "
      << todo.size() << " to run, " << jobs << " at a time (" << dir << ")\n";
  auto progress = [&](const std::string& event) {
    const double elapsed = since(t0);
    const int left = total - done;
    std::string remaining = "?";
    if (ran > 0) remaining = "~" + clock(ran_seconds / ran * std::ceil(static_cast<double>(left) / jobs));
    if (left == 0) remaining = "0:00";
    std::ostringstream line;
    line << "[" << done << "/" << total << " cells] elapsed " << clock(elapsed) << ", remaining " << remaining;
    if (!failed.empty()) line << ", " << failed.size() << " failed";
    if (tty)
      err << "\r\033[K" << line.str() << (event.empty() ? "" : "  " + event) << std::flush;
    else if (!event.empty())
      err << line.str() << "  " << event << "\n";
  };
  size_t next = 0;
  while (next < todo.size() || !running.empty()) {
    while (next < todo.size() && static_cast<int>(running.size()) < jobs) {
      const int k = todo[next++];
      running[startCell(binary, dir, cells[k])] = {k, std::chrono::steady_clock::now()};
      progress("started " + cells[k]["dir"].get<std::string>());
    }
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw Error(dir + ": waiting for a cell failed: " + std::strerror(errno));
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const int k = it->second.first;
    const double seconds = since(it->second.second);
    running.erase(it);
    const std::string cdir = cells[k]["dir"].get<std::string>();
    ++done;
    if (exitCode(status) == 0 && cellFinished((fs::path(dir) / cdir).string())) {
      ran_seconds += seconds, ++ran;
      std::ostringstream e;
      e << "finished " << cdir << " in " << std::fixed << std::setprecision(1) << seconds << " s";
      progress(e.str());
    } else {
      failed.push_back(cdir);
      progress("FAILED " + cdir + " (exit " + std::to_string(exitCode(status)) + ", see " + cdir + "/beslam.log)");
    }
  }
  if (tty) err << "\n";
  err << "bench: " << total - static_cast<int>(failed.size()) << " of " << total << " cells finished, " << ran
      << " run in " << clock(since(t0)) << "\n";
  return failed;
}

void writeDescription(const std::string& dir, const json& bench) {
  makeDirectories(dir);
  const std::string path = (fs::path(dir) / "bench.json").string();
  // A folder is bound to one matrix: resuming with another matrix would mix incomparable cells.
  if (fs::exists(path)) {
    const json old = readBench(dir);
    if (old.value("matrix", "") != bench["matrix"] || old["cells"] != bench["cells"]) {
      const std::string moved = path + ".previous";
      fs::rename(path, moved);
      std::cerr << "bench: the matrix changed since " << path << " was written; the old description is in " << moved
                << " (finished cells with the same folder are still reused)\n";
    }
  }
  writeFileAtomic(path, bench.dump(1) + "\n");
}

void finish(const std::string& dir, std::ostream& out) {
  scoreCells(dir);
  const json tables = writeTables(dir);
  report::writeBenchReport(dir);
  out << readFile((fs::path(dir) / "tables.md").string()) << "\n"
      << "tables: " << dir << "/tables.md, tables.json and CSV files beside them\n"
      << "report: " << dir << "/report/index.html\n";
}

}  // namespace

void scoreCells(const std::string& out_dir) {
  const json bench = readBench(out_dir);
  for (const auto& c : bench["cells"]) {
    if (!c.contains("score")) continue;
    const fs::path dir = fs::path(out_dir) / c.at("dir").get<std::string>();
    if (!cellFinished(dir.string())) continue;
    const auto run_time = fs::last_write_time(dir / "summary.json");
    for (const auto& step_json : c["score"]) {
      const std::string step = step_json.get<std::string>();
      const fs::path score = dir / ("eval_" + step + ".json");
      std::error_code ec;
      if (fs::exists(score, ec) && fs::last_write_time(score, ec) >= run_time) continue;
      const std::vector<std::string> args = {"--run", dir.string(), "--json", score.string()};
      std::ostringstream quiet, message;
      int status = 2;
      if (step == "motion")
        status = motion_score::runCommand(args, quiet, message);
      else if (step == "objects")
        status = object_score::runCommand(args, quiet, message);
      else if (step == "static_map")
        status = static_map::runEvalCommand(args, quiet, message);
      else
        message << "unknown scoring step";
      if (status != 0) {
        std::string why = message.str();
        while (!why.empty() && why.back() == '\n') why.pop_back();
        throwAt(dir.string(), "scoring step '" + step + "' failed: " + why);
      }
    }
  }
}

int runBenchCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  try {
    std::string matrix_path, out_dir, emit, merge_dir, cell_dir;
    std::vector<int64_t> seeds;
    int jobs = 1, cell = -1;
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= args.size()) throw Usage(a + " needs a value");
        return args[++i];
      };
      if (a == "--help" || a == "-h") {
        out << kUsage;
        return 0;
      } else if (a == "--out")
        out_dir = value();
      else if (a == "--jobs") {
        jobs = cliInteger("--jobs", value(), 1, 256);
      } else if (a == "--seeds") {
        seeds = seedList(value());
      } else if (a == "--emit") {
        emit = value();
        if (emit != "slurm") throw Usage("--emit: only 'slurm' is supported, got '" + emit + "'");
      } else if (a == "--merge")
        merge_dir = value();
      else if (a == "--cell") {
        cell = cliInteger("--cell", value(), 0, 1'000'000);
        if (i + 1 >= args.size()) throw Usage("--cell K DIR: the bench folder is missing");
        cell_dir = args[++i];
      } else if (!a.empty() && a[0] == '-')
        throw Usage("unknown option " + a);
      else if (matrix_path.empty())
        matrix_path = a;
      else
        throw Usage("more than one matrix file given");
    }

    if (!merge_dir.empty()) {
      if (!matrix_path.empty() || cell >= 0 || !emit.empty())
        throw Usage("--merge DIR takes no matrix file, --cell or --emit");
      const json bench = readBench(merge_dir);
      finish(merge_dir, out);
      return 0;
    }
    if (cell >= 0 || !cell_dir.empty()) {
      if (!matrix_path.empty()) throw Usage("--cell K DIR takes no matrix file");
      const json bench = readBench(cell_dir);
      if (cell < 0 || cell >= static_cast<int>(bench["cells"].size()))
        throwAt((fs::path(cell_dir) / "bench.json").string(),
                "no cell " + std::to_string(cell) + " (cells 0 to " + std::to_string(bench["cells"].size() - 1) + ")");
      const json& c = bench["cells"][cell];
      const fs::path dir = fs::path(cell_dir) / c["dir"].get<std::string>();
      if (cellFinished(dir.string())) {
        out << "cell " << cell << " (" << c["dir"].get<std::string>() << "): already finished\n";
        return 0;
      }
      const auto t0 = std::chrono::steady_clock::now();
      int status = 0;
      const pid_t pid = startCell(selfExe(), cell_dir, c);
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (exitCode(status) != 0 || !cellFinished(dir.string()))
        throwAt(dir.string(), "cell " + std::to_string(cell) + " failed (exit " + std::to_string(exitCode(status)) +
                                  "); its output is in " + (dir / "beslam.log").string());
      out << "cell " << cell << " (" << c["dir"].get<std::string>() << "): finished in " << std::fixed
          << std::setprecision(1) << s << " s\n";
      return 0;
    }

    if (matrix_path.empty()) throw Usage("no matrix file given");
    Matrix m = loadMatrix(matrix_path);
    if (!seeds.empty()) m.seeds = seeds;
    if (out_dir.empty()) out_dir = "out/bench/" + m.name;
    out_dir = fs::absolute(out_dir).lexically_normal().string();
    if (out_dir.size() > 1 && out_dir.back() == '/') out_dir.pop_back();
    if (emit == "slurm") {  // every value in the script is quoted where a shell reads it, checked where none does
      scriptSafe(out_dir, "--out");
      scriptSafe(m.name, "name");
    }
    const std::vector<Cell> cells = makeCells(m, out_dir);
    const std::string binary = selfExe();
    const json bench = describe(m, cells, binary);
    writeDescription(out_dir, bench);

    if (emit == "slurm") {
      const std::string script = (fs::path(out_dir) / "bench.sbatch").string();
      const std::string matrix = scriptSafe(fs::absolute(m.path).lexically_normal().string(), "matrix file");
      makeDirectories((fs::path(out_dir) / "slurm").string());
      std::ostringstream s;
      s << "#!/bin/bash\n"
        << "# " << m.name << ": " << cells.size() << " cells of " << shellQuote(matrix)
        << ", one Slurm array task a cell.\n"
        << "# Written by `beslam bench --emit slurm`. Submit:  sbatch " << shellQuote(script) << "\n"
        << "# then, when the array is done:                beslam bench --merge " << shellQuote(out_dir) << "\n"
        << "# A task whose cell is already finished exits at once; resubmit to rerun failed cells.\n"
        << "# The binary, plugins, data and this folder must be at the same paths on every node.\n"
        << "#SBATCH --job-name=\"beslam-" << m.name << "\"\n"
        << "#SBATCH --array=0-" << cells.size() - 1 << "\n"
        << "#SBATCH --cpus-per-task=1\n"
        << "#SBATCH --output=\"" << out_dir << "/slurm/%A_%a.out\"\n"
        << "set -euo pipefail\n"
        << ": \"${SLURM_ARRAY_TASK_ID:?not set: run this with sbatch, or set it to a cell number}\"\n"
        << "exec " << shellQuote(binary) << " bench --cell \"$SLURM_ARRAY_TASK_ID\" " << shellQuote(out_dir) << "\n";
      writeFileAtomic(script, s.str());
      fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                      fs::perm_options::add);
      out << "slurm: " << script << " (" << cells.size() << " array tasks, cells listed in " << out_dir
          << "/bench.json)\n  sbatch " << script << "\n  beslam bench --merge " << out_dir << "   # when it is done\n";
      return 0;
    }

    const std::vector<std::string> failed = runCells(bench, out_dir, jobs, err);
    finish(out_dir, out);
    if (!failed.empty())
      throwAt(out_dir, std::to_string(failed.size()) + " of " + std::to_string(cells.size()) +
                           " cells failed; first: " + failed.front() +
                           "/beslam.log (rerun the same command to retry them)");
    return 0;
  } catch (const Usage& e) {
    err << "beslam bench: usage error: " << e.what() << "\n" << kUsage;
    return 2;
  } catch (const Error& e) {
    err << "beslam: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace beslam::bench
