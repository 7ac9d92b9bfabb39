// Every pipeline shipped in configs/ loads, validates and resolves against the built-in plugins, so a
// renamed setting or plugin can't leave a shipped pipeline broken.
#include <gtest/gtest.h>

#include <filesystem>

#include "beslam/common/error.hpp"
#include "beslam/pipeline/spec.hpp"
#include "beslam/registry/registry.hpp"

namespace fs = std::filesystem;

TEST(ShippedConfigs, EveryPipelineResolves) {
  beslam::registry::Registry registry;
  registry.addSearchPath(PLUGIN_DIR);
  registry.scan();
  ASSERT_TRUE(registry.problems().empty()) << registry.problems().front();
  int checked = 0;
  const fs::path root = fs::path(BESLAM_SOURCE_DIR) / "configs";
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    // configs/synth holds synthetic-world presets, configs/bench bench matrices (bench_test checks
    // those), not pipelines.
    if (entry.path().extension() != ".yaml" || entry.path().parent_path() == root / "synth" ||
        entry.path().parent_path() == root / "bench")
      continue;
    SCOPED_TRACE(entry.path().string());
    try {
      beslam::pipeline::PipelineSpec spec = beslam::pipeline::loadPipeline(entry.path().string());
      beslam::pipeline::resolvePlugins(spec, registry);
      EXPECT_NE(spec.slots.at("backend").plugin, nullptr);
    } catch (const beslam::Error& e) {
      ADD_FAILURE() << e.what();
    }
    ++checked;
  }
  EXPECT_GE(checked, 3);
}
