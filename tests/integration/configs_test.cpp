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
  for (const auto& entry : fs::directory_iterator(fs::path(BESLAM_SOURCE_DIR) / "configs")) {
    if (entry.path().extension() != ".yaml") continue;
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
