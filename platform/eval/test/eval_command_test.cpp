#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <sstream>

#include "beslam/common/file_io.hpp"
#include "beslam/eval/eval.hpp"
#include "test_support.hpp"

using beslam::eval::runEvalCommand;

namespace {

struct CommandRun {
  int code = -1;
  std::string out, err;
};

CommandRun run(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  CommandRun r;
  r.code = runEvalCommand(args, out, err);
  r.out = out.str();
  r.err = err.str();
  return r;
}

std::size_t lines(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

class EvalCommand : public beslam::eval::test::ScratchDir {
 protected:
  void SetUp() override {
    ScratchDir::SetUp();
    ref_ = path("ref.tum");
    est_ = path("est.tum");
    beslam::trajectory::Trajectory est = beslam::eval::test::helix(40);
    for (auto& T_world_cam : est.poses) T_world_cam.translation() += Eigen::Vector3d(0.0, 0.3, 0.4);
    beslam::trajectory::writeTum(ref_, beslam::eval::test::helix(40));
    beslam::trajectory::writeTum(est_, est);
  }
  std::string ref_, est_;
};

}  // namespace

TEST_F(EvalCommand, HelpPrintsUsageAndSucceeds) {
  const CommandRun r = run({"--help"});
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("usage: beslam eval --ref FILE --est FILE"), std::string::npos);
  EXPECT_TRUE(r.err.empty());
}

TEST_F(EvalCommand, UsageErrorsReturnTwoWithOneLine) {
  const std::vector<std::vector<std::string>> bad = {
      {},
      {"--ref", "a.txt"},
      {"--ref", "a", "--est", "b", "--align", "sim2"},
      {"--ref", "a", "--est", "b", "--format", "euroc"},
      {"--ref", "a", "--est", "b", "--delta", "0"},
      {"--ref", "a", "--est", "b", "--delta", "1.5"},
      {"--ref", "a", "--est", "b", "--max-diff", "abc"},
      {"--ref", "a", "--est", "b", "--max-diff", "-1"},
      {"--ref", "a", "--est", "b", "--offset", "nan"},
      {"--ref", "a", "--est", "b", "--frobnicate"},
      {"--ref", "a", "--est", "b", "stray"},
      {"--ref", "a", "--est"},
  };
  for (const auto& args : bad) {
    const CommandRun r = run(args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("beslam eval: ", 0), 0u) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
  EXPECT_NE(run({"--ref", "a", "--est", "b", "--frobnicate"}).err.find("'--frobnicate'"), std::string::npos);
}

TEST_F(EvalCommand, InputErrorsReturnOneNamingTheFile) {
  const std::string missing = path("missing.tum");
  CommandRun r = run({"--ref", ref_, "--est", missing});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find(missing), std::string::npos) << r.err;

  const std::string broken = write("broken.tum", "# header\n100 0 0 0 0 0 0 1\n100.1 0 0 0 0 0 1\n");
  r = run({"--ref", ref_, "--est", broken});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find(broken + ":3: expected 8 numbers per row"), std::string::npos) << r.err;

  r = run({"--ref", ref_, "--est", est_, "--offset", "50"});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("no timestamps match"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(est_), std::string::npos) << r.err;

  const std::string empty = write("empty.tum", "");
  r = run({"--ref", empty, "--est", est_});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find(empty + ": no poses"), std::string::npos) << r.err;

  r = run({"--ref", ref_, "--est", est_, "--json", path("no_dir/out.json")});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find(path("no_dir/out.json")), std::string::npos) << r.err;
}

TEST_F(EvalCommand, EvaluatesAndWritesJson) {
  const std::string json_path = path("result.json");
  const CommandRun r = run({"--ref", ref_, "--est=" + est_, "--format", "tum", "--align", "none", "--max-diff", "0.02",
                            "--delta", "2", "--json", json_path});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.err.empty());
  EXPECT_NE(r.out.find("APE trans (m)"), std::string::npos) << r.out;
  const nlohmann::json j = nlohmann::json::parse(beslam::readFile(json_path));
  EXPECT_EQ(j["pairs"], 40);
  EXPECT_EQ(j["alignment"]["type"], "none");
  EXPECT_NEAR(j["ape"]["trans"]["rmse"].get<double>(), 0.5, 1e-12);  // |(0, 0.3, 0.4)|
  EXPECT_NEAR(j["ape"]["trans"]["std"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(j["rpe"]["trans"]["max"].get<double>(), 0.0, 1e-12);
}

TEST(EvalCommandReference, KittiThroughTheCommandLine) {
  const std::string dir = beslam::eval::test::evoDataDir();
  if (dir.empty()) GTEST_SKIP() << "shared evo data (" << BESLAM_SHARED_DATA << "/evo) not found";
  const std::string json_path =
      (std::filesystem::temp_directory_path() / ("beslam_eval_kitti_" + std::to_string(::getpid()) + ".json")).string();
  const CommandRun r = run(
      {"--ref", dir + "/KITTI_00_gt.txt", "--est", dir + "/KITTI_00_ORB.txt", "--align", "sim3", "--json", json_path});
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(beslam::readFile(json_path));
  std::filesystem::remove(json_path);
  EXPECT_EQ(j["pairs"], 4541);
  EXPECT_NEAR(j["ape"]["trans"]["rmse"].get<double>(), 0.937709074, 1e-6 * 0.937709074);
  EXPECT_NEAR(j["rpe"]["rot"]["rmse"].get<double>(), 0.114973521, 1e-6 * 0.114973521);
}
