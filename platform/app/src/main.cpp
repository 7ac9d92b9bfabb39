// `beslam`: the command-line front of the host.
//   beslam run PIPELINE.yaml [--set key=value]... [--out DIR] [--plugin-path DIR]... [--quiet]
//              [--load-map FILE] [--save-map FILE] [--localise-only] [--allow-writable-plugin-dirs]
//              [--overwrite]
//   beslam plugins [--plugin-path DIR]... [--json] [--allow-writable-plugin-dirs]
//   beslam eval --ref FILE --est FILE [...]
//   beslam eval-motion --run DIR [...]
//   beslam eval-objects --run DIR [...]
//   beslam eval-static-map --run DIR [...]
//   beslam synth --config FILE --out DIR [--set key=value]...
//   beslam bench MATRIX.yaml [--out DIR] [--jobs N] [--emit slurm] | --merge DIR | --cell K DIR
//   beslam report RUN_DIR [--out DIR]
//   beslam X ...   any other command runs the executable beslam-X next to beslam (git-style), e.g.
//                  beslam vocab train ... runs beslam-vocab train ...
// Every failure prints one line "beslam: error: <file or plugin>: <cause>" and exits non-zero
// (2 for a usage error, 1 for anything else).
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "beslam/bench/bench.hpp"
#include "beslam/common/error.hpp"
#include "beslam/common/interrupt.hpp"
#include "beslam/eval/eval.hpp"
#include "beslam/motion_score/motion_score.hpp"
#include "beslam/object_score/object_score.hpp"
#include "beslam/pipeline/runner.hpp"
#include "beslam/pipeline/spec.hpp"
#include "beslam/registry/registry.hpp"
#include "beslam/report/report.hpp"
#include "beslam/sdk/cli_args.hpp"
#include "beslam/static_map/score.hpp"
#ifdef BESLAM_WITH_SIM
#include "beslam/sim/synth.hpp"
#endif

namespace {

constexpr const char* kUsage =
    "usage: beslam <command> [options]\n"
    "\n"
    "commands:\n"
    "  run PIPELINE.yaml   run a pipeline (see configs/ and docs/pipelines.md)\n"
    "  plugins             list every plugin found, with its configuration schema\n"
    "  eval                APE/RPE of a trajectory against a reference (evo's definitions)\n"
    "  eval-motion         a run's static/dynamic calls scored against synthetic truth\n"
    "  eval-objects        a run's reconstructed objects scored against synthetic truth (Table II)\n"
    "  eval-static-map     a run's static_map.bt (OctoMap) scored against synthetic truth\n"
    "  synth               render a synthetic sequence with full ground truth\n"
    "  bench MATRIX.yaml   pipelines x sequences x seeds: runs, tables, report (docs/benchmarks.md)\n"
    "  report RUN_DIR      a self-contained HTML report of one run\n"
    "  vocab               ORB vocabularies for backend_orb (beslam-vocab: train, info, rank)\n"
    "\n"
    "`beslam <command> --help` describes a command's options.\n";

constexpr const char* kRunUsage =
    "usage: beslam run PIPELINE.yaml [options]\n"
    "\n"
    "  --set KEY=VALUE     override a pipeline value, e.g. --set dataset.sequence=00 (repeatable)\n"
    "  --out DIR           output folder (default: output.dir of the pipeline); --out=DIR works too.\n"
    "                      Locked while the run writes; one holding a previous run's outputs is refused\n"
    "  --overwrite         replace a previous run's outputs in the output folder (its own files only)\n"
    "  --plugin-path DIR   also look for plugins in DIR (repeatable; BESLAM_PLUGIN_PATH works too)\n"
    "  --allow-writable-plugin-dirs\n"
    "                      use plugin folders and libraries that group or others can write to (refused\n"
    "                      otherwise: whoever can write there chooses the code beslam runs)\n"
    "  --quiet             no progress line, warnings only\n"
    "  --verbose           plugins' info messages too\n"
    "  --load-map FILE     start from a saved map (backend.load_map; backend_orb)\n"
    "  --save-map FILE     save the map at the end of the run, also when interrupted (backend.save_map)\n"
    "  --localise-only     track against the loaded map without changing it (backend.localisation_only)\n"
    "\n"
    "Writes trajectory.tum/.kitti, trajectory_online.tum, keyframes.tum, pipeline.resolved.yaml,\n"
    "timing.csv, summary.json, and objects.txt, masks/, map_points.ply where the pipeline makes them.\n"
    "trajectory.tum/.kitti grow as frames finish, so a run that fails or is killed keeps its tracked frames;\n"
    "summary.json's status says how the run ended (completed, interrupted, failed: reason). A run with fewer\n"
    "than output.min_tracked_share of its frames in the final trajectory exits 1 after writing its outputs.\n";

constexpr const char* kPluginsUsage =
    "usage: beslam plugins [--plugin-path DIR]... [--json] [--allow-writable-plugin-dirs]\n"
    "\n"
    "Loads every library (*.so) in the search path and lists each file it loaded, every plugin (id, kind,\n"
    "version, library and configuration schema) and every library that was refused, with the reason.\n"
    "Folders and libraries that group or others can write to are refused unless\n"
    "--allow-writable-plugin-dirs is given.\n";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string takeValue(const std::vector<std::string>& args, size_t& i) {
  if (i + 1 >= args.size()) throw UsageError(args[i] + " needs a value");
  return args[++i];
}

// BESLAM_DEBUG_SIGNAL_AT=FRAME:SIGNAL (e.g. 3:SIGTERM, or 3:SIGKILL) makes the run send itself SIGNAL when frame FRAME
// is done: the tests interrupt a run at a chosen frame through the real signal path, with no timing.
std::function<void(int64_t)> debugSignalAt() {
  const char* value = std::getenv("BESLAM_DEBUG_SIGNAL_AT");
  if (!value || !*value) return {};
  const std::string text(value);
  const size_t colon = text.find(':');
  int64_t frame = -1;
  try {
    frame = std::stoll(text.substr(0, colon));
  } catch (const std::exception&) {
  }
  const std::string name = colon == std::string::npos ? "" : text.substr(colon + 1);
  // SIGKILL stands for a crash or a power cut: the run ends there, with no chance to write anything.
  const int signal_number = name == "SIGINT" ? SIGINT : name == "SIGTERM" ? SIGTERM : name == "SIGKILL" ? SIGKILL : 0;
  if (frame < 0 || signal_number == 0)
    throw UsageError("BESLAM_DEBUG_SIGNAL_AT must be FRAME:SIGINT, FRAME:SIGTERM or FRAME:SIGKILL, not '" + text + "'");
  return [frame, signal_number](int64_t done) {
    if (done == frame) std::raise(signal_number);
  };
}

// --load-map / --save-map FILE as the --set of the backend's path setting: FILE relative to the working
// folder (a pipeline's own paths are relative to the pipeline file), single-quoted for YAML.
std::string backendPathOverride(const char* key, const std::string& file) {
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(file, ec);
  if (file.empty() || ec) throw UsageError(std::string("run: not a file name for ") + key + ": '" + file + "'");
  std::string quoted;
  for (char c : absolute.lexically_normal().string()) quoted += c == '\'' ? "''" : std::string(1, c);
  return std::string("backend.") + key + "='" + quoted + "'";
}

// " 3 17 42": at most 20 frame numbers, then " ... (N in all)".
std::string frameList(const std::vector<int64_t>& frames) {
  std::string s;
  for (size_t i = 0; i < frames.size() && i < 20; ++i) s += " " + std::to_string(frames[i]);
  if (frames.size() > 20) s += " ... (" + std::to_string(frames.size()) + " in all)";
  return s;
}

bool wantsHelp(const std::vector<std::string>& args) {
  for (const auto& a : args)
    if (a == "--help" || a == "-h") return true;
  return false;
}

int runCommand(const std::vector<std::string>& args) {
  if (wantsHelp(args)) {
    std::cout << kRunUsage;
    return 0;
  }
  std::string pipeline_path;
  std::vector<std::string> overrides, plugin_paths;
  bool allow_writable = false;
  beslam::pipeline::RunOptions options;
  options.progress = true;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--set")
      overrides.push_back(takeValue(args, i));
    else if (a.rfind("--set=", 0) == 0)
      overrides.push_back(a.substr(6));
    else if (a == "--out")
      options.output_dir = takeValue(args, i);
    else if (a.rfind("--out=", 0) == 0 && a.size() > 6)
      options.output_dir = a.substr(6);
    else if (a == "--plugin-path")
      plugin_paths.push_back(takeValue(args, i));
    else if (a.rfind("--plugin-path=", 0) == 0)
      plugin_paths.push_back(a.substr(14));
    else if (a == "--allow-writable-plugin-dirs")
      allow_writable = true;
    else if (a == "--overwrite")
      options.overwrite = true;
    else if (a == "--quiet")
      options.progress = false;
    else if (a == "--verbose")
      options.log_level = BESLAM_LOG_INFO;
    else if (a == "--load-map")
      overrides.push_back(backendPathOverride("load_map", takeValue(args, i)));
    else if (a == "--save-map")
      overrides.push_back(backendPathOverride("save_map", takeValue(args, i)));
    else if (a == "--localise-only")
      overrides.push_back("backend.localisation_only=true");
    else if (!a.empty() && a[0] == '-')
      throw UsageError("run: unknown option " + a);
    else if (pipeline_path.empty())
      pipeline_path = a;
    else
      throw UsageError("run: more than one pipeline file given");
  }
  if (pipeline_path.empty()) throw UsageError("run: no pipeline file given");

  beslam::pipeline::PipelineSpec spec = beslam::pipeline::loadPipeline(pipeline_path, overrides);
  beslam::registry::Registry registry;
  registry.allowWritable(allow_writable);
  for (const auto& p : plugin_paths) registry.addSearchPath(p);
  for (const auto& p : spec.plugin_paths) registry.addSearchPath(p);
  std::vector<std::string> plugin_ids;  // only the libraries named after the pipeline's plugins (<id>.so)
  for (const auto& [slot_name, slot] : spec.slots)
    if (!slot.plugin_id.empty()) plugin_ids.push_back(slot.plugin_id);
  registry.loadFor(plugin_ids);
  // Refused libraries matter only if the pipeline names one of their plugins, and then the error
  // says why they were refused; list them all, and every library loaded, with --verbose.
  if (options.log_level <= BESLAM_LOG_INFO) {
    for (const auto& file : registry.loadedFiles()) std::cerr << "beslam: loaded " << file << "\n";
    for (const auto& problem : registry.problems()) std::cerr << "beslam: skipped " << problem << "\n";
  }
  beslam::pipeline::resolvePlugins(spec, registry);
  // SIGINT/SIGTERM end the run after the current frame, with every output written; a second one aborts.
  beslam::InterruptGuard interrupts;
  options.stop_requested = [] { return beslam::InterruptGuard::requested() != 0; };
  options.stop_reason = [] { return beslam::signalName(beslam::InterruptGuard::requested()); };
  options.after_frame = debugSignalAt();
  const beslam::pipeline::RunSummary s = beslam::pipeline::run(spec, options);

  std::cout << "frames " << s.frames << ", tracked " << s.tracked << ", keyframes " << s.keyframes << ", median "
            << s.median_frame_ms << " ms/frame, " << s.fps << " frames/s, peak memory "
            << static_cast<long>(std::lround(s.peak_rss_mb)) << " MiB\n";
  if (!s.untracked.empty()) {
    std::cout << "untracked frames:" << frameList(s.untracked) << "\n";
  }
  if (s.has_ape)
    std::cout << "APE translation RMSE " << s.ape_trans_rmse << " m (" << spec.evaluation.alignment << ", scale "
              << s.ape_alignment_scale << "), RPE translation RMSE " << s.rpe_trans_rmse << " m\n";
  // SE(3) APE measures a trajectory in metres: printed only for a metric map (else it is the map's unit
  // against metres, a number without meaning).
  if (s.has_ape && s.metric_from_frame >= 0)
    std::cout << "APE (both alignments): Sim(3) " << s.ape_sim3_rmse << " m, SE(3) " << s.ape_se3_rmse << " m\n";
  else if (s.has_ape)
    std::cout << "APE Sim(3) " << s.ape_sim3_rmse << " m; no SE(3) APE: the map has no scale (monocular unit)\n";
  if (!s.evaluation_error.empty()) std::cout << "no APE: " << s.evaluation_error << "\n";
  if (s.metric_from_frame >= 0)
    std::cout << "map in metres from frame " << s.metric_from_frame << " (camera height " << s.camera_height << " m)"
              << (s.motion_replayed_frames == 0 ? std::string()
                  : spec.run.motion_replay_boxes
                      ? "; the motion checker ran again on the " + std::to_string(s.motion_replayed_frames) +
                            " frames before, with metric poses"
                      : "; the motion checker watched the backend's poses of the " +
                            std::to_string(s.motion_replayed_frames) + " frames before")
              << (s.world_moves > 0 ? "; the backend moved it " + std::to_string(s.world_moves) +
                                          " times (loop corrections, changes of scale, local BA under the camera)"
                                    : std::string())
              << "\n";
  else
    std::cout << "map scale: not metric (monocular unit)\n";
  if (s.detections_static + s.detections_dynamic + s.detections_unknown > 0)
    std::cout << "detections: " << s.detections_static << " static, " << s.detections_dynamic << " dynamic, "
              << s.detections_unknown << " unknown; frames with masks " << s.frames_with_masks << "\n";
  {
    double features_static = 0, tracked_static = 0;
    for (const auto& [name, value] : s.backend_counters) {
      if (name == "features_static") features_static = value;
      if (name == "tracked_static") tracked_static = value;
      if (name == "relocalisations" && value > 0)
        std::cout << "relocalisations: " << value << " (frames" << frameList(s.relocalisation_frames) << ")\n";
      if (name == "loop_closures" && value > 0) {
        std::cout << "loop closures: " << value << " (";
        for (size_t k = 0; k < s.loop_closures.size() && k < 20; ++k)
          std::cout << (k ? ", " : "") << "frame " << s.loop_closures[k].frame << " corrected by "
                    << s.loop_closures[k].correction << (s.metric_from_frame >= 0 ? " m" : " map units");
        std::cout << (s.loop_closures.size() > 20 ? ", ..." : "") << ")\n";
      }
      if (name == "loop_object_rejections" && value > 0)
        std::cout << "loop candidates rejected by the parked-car check: " << value << "\n";
      if (name == "relocalisation_object_rejections" && value > 0)
        std::cout << "relocalisation candidates rejected by the parked-car check: " << value << "\n";
    }
    if (features_static > 0 || s.map_points_static > 0)
      std::cout << "static objects: " << features_static << " features, " << tracked_static
                << " tracked map-point matches, " << s.map_points_static << " of " << s.map_points
                << " final map points\n";
  }
  if (s.objects_reconstructed >= 0)
    std::cout << "objects reconstructed: " << s.objects_reconstructed << " (" << s.objects_with_mesh
              << " with a mesh), objects.json\n";
  std::cout << "output: " << s.output_dir << "\n";
  if (s.interrupted) {
    std::cerr << "beslam: interrupted by " << s.interrupted_by << " after frame " << s.last_frame << "; outputs of the "
              << s.frames << " frames done are written\n";
    return 128 + beslam::InterruptGuard::requested();  // the shell's convention for a signalled job
  }
  return 0;
}

int pluginsCommand(const std::vector<std::string>& args) {
  if (wantsHelp(args)) {
    std::cout << kPluginsUsage;
    return 0;
  }
  beslam::registry::Registry registry;
  bool json_out = false;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--plugin-path")
      registry.addSearchPath(takeValue(args, i));
    else if (args[i].rfind("--plugin-path=", 0) == 0)
      registry.addSearchPath(args[i].substr(14));
    else if (args[i] == "--allow-writable-plugin-dirs")
      registry.allowWritable(true);
    else if (args[i] == "--json")
      json_out = true;
    else
      throw UsageError("plugins: unknown option " + args[i]);
  }
  registry.scan();
  if (json_out) {
    nlohmann::json j;
    j["search_paths"] = registry.searchPaths();
    j["loaded"] = registry.loadedFiles();
    j["plugins"] = nlohmann::json::array();
    for (const auto& p : registry.plugins()) {
      nlohmann::json pj{{"id", p.id},
                        {"kind", beslam::registry::kindName(p.kind)},
                        {"version", p.version},
                        {"abi", std::to_string(p.abi_version >> 16) + "." + std::to_string(p.abi_version & 0xffff)},
                        {"name", p.name},
                        {"description", p.description},
                        {"library", p.library_path}};
      pj["config"] = nlohmann::json::array();
      for (const auto& f : p.fields) {
        nlohmann::json fj{{"key", f.key},
                          {"type", beslam::registry::configTypeName(f.type)},
                          {"required", f.required},
                          {"default", f.default_value},
                          {"doc", f.doc}};
        if (f.min_value <= f.max_value) fj["range"] = {f.min_value, f.max_value};
        if (!f.choices.empty()) fj["choices"] = f.choices;
        pj["config"].push_back(fj);
      }
      j["plugins"].push_back(pj);
    }
    j["problems"] = registry.problems();
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::cout << "search path:";
  for (const auto& p : registry.searchPaths()) std::cout << ' ' << p;
  std::cout << "\n";
  for (const auto& file : registry.loadedFiles()) std::cout << "loaded: " << file << "\n";
  std::cout << "\n";
  for (const auto& p : registry.plugins()) {
    std::cout << p.id << "  (" << beslam::registry::kindName(p.kind) << ", version " << p.version << ", ABI "
              << (p.abi_version >> 16) << "." << (p.abi_version & 0xffff) << ")\n"
              << "  " << p.name << ": " << p.description << "\n"
              << "  library: " << p.library_path << "\n";
    for (const auto& f : p.fields) {
      std::cout << "    " << f.key << " (" << beslam::registry::configTypeName(f.type);
      if (f.min_value <= f.max_value) std::cout << ", " << f.min_value << " to " << f.max_value;
      if (!f.choices.empty()) std::cout << ", one of " << f.choices;
      std::cout << (f.required ? ", required" : ", default " + f.default_value) << "): " << f.doc << "\n";
    }
    std::cout << "\n";
  }
  for (const auto& problem : registry.problems()) std::cout << "refused: " << problem << "\n";
  std::cout << registry.plugins().size() << " plugins";
  if (!registry.problems().empty()) std::cout << ", " << registry.problems().size() << " libraries refused";
  std::cout << "\n";
  return 0;
}

// Git-style extension: `beslam X args...` replaces this process with beslam-X (next to this binary)
// run with the same arguments, so its output and exit code are the command's. Returns when there is no
// such executable; throws when there is one that cannot be run.
void runExternalCommand(const std::string& command, char** argv) {
  if (command.empty() || command.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_-") != std::string::npos)
    return;
  std::error_code ec;
  std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) self = std::filesystem::absolute(argv[0], ec);
  const std::string tool = (self.parent_path() / ("beslam-" + command)).string();
  if (::access(tool.c_str(), X_OK) != 0) return;
  std::vector<char*> tool_argv{const_cast<char*>(tool.c_str())};
  for (char** a = argv + 2; *a; ++a) tool_argv.push_back(*a);
  tool_argv.push_back(nullptr);
  std::cout.flush();
  ::execv(tool.c_str(), tool_argv.data());
  throw beslam::Error(tool + ": cannot run: " + std::strerror(errno));
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  args.erase(args.begin());
  const auto dispatch = [&]() -> int {
    if (command == "run") return runCommand(args);
    if (command == "plugins") return pluginsCommand(args);
    if (command == "eval") return beslam::eval::runEvalCommand(args, std::cout, std::cerr);
    if (command == "bench") return beslam::bench::runBenchCommand(args, std::cout, std::cerr);
    if (command == "report") return beslam::report::runReportCommand(args, std::cout, std::cerr);
    if (command == "eval-motion") return beslam::motion_score::runCommand(args, std::cout, std::cerr);
    if (command == "eval-objects") return beslam::object_score::runCommand(args, std::cout, std::cerr);
    if (command == "eval-static-map") return beslam::static_map::runEvalCommand(args, std::cout, std::cerr);
#ifdef BESLAM_WITH_SIM
    if (command == "synth") return beslam::sim::runSynthCommand(args, std::cout, std::cerr);
#endif
    if (command == "--version" || command == "version") {
      std::cout << "beslam " BESLAM_VERSION " (plugin ABI " << BESLAM_ABI_VERSION_MAJOR << "."
                << BESLAM_ABI_VERSION_MINOR << ")\n";
      return 0;
    }
    runExternalCommand(command, argv);  // returns only when there is no beslam-<command>
    throw UsageError("unknown command '" + command + "'");
  };
  return beslam::cli::runMain<UsageError>(dispatch, std::cerr, kUsage,
                                          "beslam: usage error: ", "beslam: error: ", "beslam: internal error: ");
}
