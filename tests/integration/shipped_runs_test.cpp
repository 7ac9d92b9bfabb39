// Every pipeline shipped in configs/ runs a few frames end to end on the data it names (the KITTI
// excerpts in ../shared, synthetic sequences rendered short), so a shipped pipeline cannot fail on the
// shipped data: each run exits 0 and its summary.json says "completed". A pipeline whose data or model
// files are absent is skipped with a message naming them. The runs are short (10 frames), so the
// tracked share is not checked here (output.min_tracked_share=0): whole runs check it (run_test, bench).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/pipeline/spec.hpp"
#include "beslam/registry/registry.hpp"
#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;

namespace {

using beslam::test::readText;

std::string quote(const std::string& s) {
  std::string o = "'";
  for (char c : s) o += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return o + "'";
}

// Why the pipeline cannot run here (a missing dataset root or plugin file), or empty.
std::string missingInput(const fs::path& file, const beslam::registry::Registry& registry) {
  beslam::pipeline::PipelineSpec spec = beslam::pipeline::loadPipeline(file.string());
  std::error_code ec;
  if (spec.dataset.type != "synth" && !fs::exists(spec.dataset.root, ec)) return "no dataset " + spec.dataset.root;
  beslam::pipeline::resolvePlugins(spec, registry);
  for (const auto& [name, slot] : spec.slots) {
    if (!slot.plugin) continue;
    for (const beslam_config_value& v : slot.config.values())
      if (v.type == BESLAM_CONFIG_PATH && v.text && *v.text && !fs::exists(v.text, ec))
        return std::string("no ") + v.text + " (" + name + "." + v.key + ")";
  }
  return {};
}

}  // namespace

TEST(ShippedPipelines, EachRunsAFewFramesOnTheSharedData) {
  beslam::registry::Registry registry;
  registry.addSearchPath(PLUGIN_DIR);
  registry.scan();
  const fs::path root = fs::path(BESLAM_SOURCE_DIR) / "configs";
  const fs::path scratch = fs::temp_directory_path() / ("beslam_shipped_runs_" + std::to_string(::getpid()));
  fs::remove_all(scratch);
  fs::create_directories(scratch);
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.path().extension() == ".yaml" && entry.path().parent_path() != root / "synth" &&
        entry.path().parent_path() != root / "bench")
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  int ran = 0;
  std::string skipped;
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    std::string missing;
    try {
      missing = missingInput(file, registry);
    } catch (const beslam::Error& e) {
      ADD_FAILURE() << e.what();
      continue;
    }
    if (!missing.empty()) {
      skipped += "\n  " + fs::relative(file, root).string() + ": " + missing;
      continue;
    }
    const beslam::pipeline::PipelineSpec spec = beslam::pipeline::loadPipeline(file.string());
    const fs::path out = scratch / fs::relative(file, root).replace_extension("");
    std::string args = " --quiet --out " + quote(out.string()) + " --set output.min_tracked_share=0";
    if (spec.dataset.type == "synth") {  // rendered short, into the build tree's own cache
      const std::string set = spec.dataset.synth_set.empty() ? "frames=10" : spec.dataset.synth_set + ",frames=10";
      args += " --set dataset.root=" + quote((fs::path(BESLAM_BINARY_DIR) / "test-shipped-synth-cache").string()) +
              " --set dataset.synth_set=" + quote(set);
    } else {
      args += " --set dataset.last=" + std::to_string(spec.dataset.first + 9);
    }
    const fs::path log = scratch / (out.filename().string() + ".log");
    const std::string cmd = std::string(BESLAM_BINARY_DIR) + "/bin/beslam run " + quote(file.string()) + args + " > " +
                            quote(log.string()) + " 2>&1 < /dev/null";
    const int status = std::system(cmd.c_str());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cmd << "\n" << readText(log);
    EXPECT_NE(readText(out / "summary.json").find("\"status\": \"completed\""), std::string::npos) << readText(log);
    ++ran;
  }
  fs::remove_all(scratch);
  if (!skipped.empty()) std::cout << "[ SKIPPED ] pipelines whose inputs are absent here:" << skipped << "\n";
  if (ran == 0) GTEST_SKIP() << "no shipped pipeline has its data here:" << skipped;
}
