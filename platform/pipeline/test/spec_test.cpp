// Pipeline files: every mistake a user can make is one error naming the file, the line and the key.
#include "beslam/pipeline/spec.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "beslam/common/error.hpp"

namespace fs = std::filesystem;
using beslam::pipeline::loadPipeline;

namespace {

class PipelineSpecTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("beslam_spec_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& text) {
    const std::string path = (dir_ / "pipeline.yaml").string();
    std::ofstream(path) << text;
    return path;
  }

  // Expects loadPipeline to fail with a message containing every fragment.
  void expectError(const std::string& text, const std::vector<std::string>& fragments,
                   const std::vector<std::string>& overrides = {}) {
    const std::string path = write(text);
    try {
      loadPipeline(path, overrides);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const beslam::Error& e) {
      for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
  }

  fs::path dir_;
};

const char* kGood =
    "name: test\n"
    "dataset:\n"
    "  type: kitti_odometry\n"
    "  root: data/odometry\n"
    "  sequence: \"06\"\n"
    "backend:\n"
    "  plugin: backend_pose_replay\n"
    "  poses: poses.txt\n";

}  // namespace

TEST_F(PipelineSpecTest, LoadsAndFillsHostDefaults) {
  const auto spec = loadPipeline(write(kGood));
  EXPECT_EQ(spec.dataset.type, "kitti_odometry");
  EXPECT_EQ(spec.dataset.root, (dir_ / "data/odometry").string());  // relative to the pipeline file
  EXPECT_EQ(spec.dataset.sequence, "06");
  EXPECT_EQ(spec.dataset.last, -1);
  EXPECT_EQ(spec.evaluation.alignment, "sim3");
  EXPECT_EQ(spec.slots.at("backend").plugin_id, "backend_pose_replay");
  EXPECT_TRUE(spec.slots.at("detector").plugin_id.empty());
  EXPECT_EQ(spec.document["dataset"]["step"].as<int>(), 1);  // defaults are written back
}

TEST_F(PipelineSpecTest, SetOverridesApply) {
  const auto spec = loadPipeline(write(kGood), {"dataset.sequence=00", "dataset.last=99", "detector.plugin=x"});
  EXPECT_EQ(spec.dataset.sequence, "00");
  EXPECT_EQ(spec.dataset.last, 99);
  EXPECT_EQ(spec.slots.at("detector").plugin_id, "x");
}

// Your own camera (docs/datasets.md): the camera file and the new dataset types, from the file and from --set.
TEST_F(PipelineSpecTest, CameraFileAndOwnDataTypes) {
  EXPECT_TRUE(loadPipeline(write(kGood)).dataset.calibration.empty());
  const auto spec =
      loadPipeline(write(kGood), {"dataset.type=images", "dataset.root=frames", "dataset.calibration=cam.yaml"});
  EXPECT_EQ(spec.dataset.type, "images");
  EXPECT_EQ(spec.dataset.calibration, (dir_ / "cam.yaml").string());  // relative to the pipeline file
  EXPECT_EQ(spec.document["dataset"]["calibration"].as<std::string>(), (dir_ / "cam.yaml").string());
  for (const char* type : {"video", "euroc"})
    EXPECT_EQ(loadPipeline(write(kGood), {std::string("dataset.type=") + type}).dataset.type, type);
  const auto in_file = loadPipeline(
      write("dataset: {type: video, root: a.mp4, calibration: /cams/mine.yaml}\nbackend: {plugin: backend_orb}\n"));
  EXPECT_EQ(in_file.dataset.root, (dir_ / "a.mp4").string());
  EXPECT_EQ(in_file.dataset.calibration, "/cams/mine.yaml");
  expectError(kGood, {"dataset.type: 'webcam' is not one of", "images|video|euroc"}, {"dataset.type=webcam"});
  expectError(kGood, {"dataset.camera_override: unknown key", "calibration"}, {"dataset.camera_override.fx=700"});
}

TEST_F(PipelineSpecTest, SyntaxErrorNamesFileAndLine) {
  expectError("dataset:\n  type: kitti_odometry\n  root: [unclosed\nbackend: {plugin: a}\n",
              {"pipeline.yaml:", "YAML syntax error"});
}

// Found by the pipeline_yaml fuzzer (tests/fuzz): a map or a sequence used as a key reached yaml-cpp's
// string conversion and escaped as a YAML exception.
TEST_F(PipelineSpecTest, NonScalarKeysAreOneError) {
  expectError("? {a: 1}\n: 2\n", {"pipeline.yaml:1:", "a key must be a plain name"});
  expectError(std::string(kGood) + "output:\n  ? [x, y]\n  : 3\n", {"pipeline.yaml:", "a key must be a plain name"});
  expectError("# t: rpeAde+#lt\n:\n t: rpeAde+#lt\n:\n?  : rpeAde+#lt\n:\n", {"pipeline.yaml"});
}

// Found by the pipeline_yaml fuzzer: a path the file system refuses to look at (a name longer than
// NAME_MAX) escaped as std::filesystem_error.
TEST_F(PipelineSpecTest, UnusablePathIsOneError) {
  expectError("dataset:\n  type: kitti_odometry\n  root: " + std::string(5000, 'a') +
                  "\n  sequence: \"00\"\nbackend: {plugin: backend_pose_replay, poses: p.txt}\n",
              {"pipeline.yaml", "File name too long"});
}

TEST_F(PipelineSpecTest, UnknownKeyNamesLineAndKnownKeys) {
  expectError(std::string(kGood) + "datset: {}\n", {"pipeline.yaml:9: datset: unknown key", "known: name"});
  expectError("dataset:\n  type: tum\n  root: x\n  frist: 3\nbackend: {plugin: a}\n",
              {"pipeline.yaml:4: dataset.frist: unknown key (known: type, root, sequence"});
}

TEST_F(PipelineSpecTest, WrongTypesAndRanges) {
  expectError("dataset:\n  type: tum\n  root: x\n  first: abc\nbackend: {plugin: a}\n",
              {"pipeline.yaml:4: dataset.first: expected an integer, got 'abc'"});
  expectError("dataset:\n  type: tum\n  root: x\n  step: 0\nbackend: {plugin: a}\n",
              {"pipeline.yaml:4: dataset.step: value 0 is out of range [1, 1e+06]"});
  expectError("dataset:\n  type: tum\n  root: x\n  lidar: maybe\nbackend: {plugin: a}\n",
              {"pipeline.yaml:4: dataset.lidar: expected true or false, got 'maybe'"});
  expectError("dataset:\n  type: kitti_something\n  root: x\nbackend: {plugin: a}\n",
              {"pipeline.yaml:2: dataset.type: 'kitti_something' is not one of kitti_odometry|"});
  expectError("dataset:\n  type: tum\n  root: x\n  first: 5\n  last: 2\nbackend: {plugin: a}\n",
              {"pipeline.yaml:5: dataset.last: is before dataset.first"});
}

TEST_F(PipelineSpecTest, MissingSectionsAndSlots) {
  expectError("backend: {plugin: a}\n", {"pipeline.yaml: dataset: required section is missing"});
  expectError("dataset:\n  type: tum\nbackend: {plugin: a}\n",
              {"pipeline.yaml:2: dataset.root: required setting is missing"});
  expectError("dataset: {type: tum, root: x}\n", {"a pipeline needs a backend"});
  expectError("dataset: {type: tum, root: x}\nbackend: backend_orb\n",
              {"pipeline.yaml:2: backend: expected a map with a 'plugin' key"});
  expectError("", {"pipeline.yaml: the pipeline file is empty"});
}

TEST_F(PipelineSpecTest, BadOverridesNameTheOverride) {
  expectError(kGood, {"--set novalue: expected key=value"}, {"novalue"});
  expectError(kGood, {"pipeline.yaml (--set): dataset.first: expected an integer, got 'x'"}, {"dataset.first=x"});
}

TEST_F(PipelineSpecTest, MissingFile) {
  try {
    loadPipeline((dir_ / "nope.yaml").string());
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("nope.yaml: no such pipeline file"), std::string::npos);
  }
}

TEST_F(PipelineSpecTest, PluginSettingsValidatedAgainstSchema) {
  using beslam::registry::ConfigField;
  const std::vector<ConfigField> fields = {
      {"features", BESLAM_CONFIG_INT, false, "2000", 100, 10000, "", "features"},
      {"mode", BESLAM_CONFIG_STRING, false, "sync", 1, 0, "sync|threaded", "mode"},
      {"weights", BESLAM_CONFIG_DOUBLE_LIST, false, "[1, 2]", 0, 10, "", "weights"},
      {"model", BESLAM_CONFIG_PATH, true, "", 1, 0, "", "model"},
  };
  const std::string file = write("backend:\n  plugin: x\n  features: 50\n");
  YAML::Node doc = YAML::LoadFile(file);
  try {
    beslam::pipeline::validateSettings(doc["backend"], fields, "backend", file, "/base", {"plugin"});
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("pipeline.yaml:3: backend.features: value 50 is out of range [100, 10000]"),
              std::string::npos)
        << e.what();
  }
  doc = YAML::Load("plugin: x\nmodel: m.cfg\nweights: [3, 4.5]\n");
  const auto config = beslam::pipeline::validateSettings(doc, fields, "backend", file, "/base", {"plugin"});
  ASSERT_EQ(config.values().size(), 4u);
  EXPECT_EQ(config.values()[0].number, 2000);
  EXPECT_STREQ(config.values()[1].text, "sync");
  EXPECT_EQ(config.values()[2].list_size, 2u);
  EXPECT_EQ(config.values()[2].list[1], 4.5);
  EXPECT_STREQ(config.values()[3].text, "/base/m.cfg");
  EXPECT_EQ(doc["features"].as<int>(), 2000);  // default filled into the document
  doc = YAML::Load("plugin: x\nmodel: m\nweights: [3, 40]\n");
  EXPECT_THROW(beslam::pipeline::validateSettings(doc, fields, "backend", file, "/base", {"plugin"}), beslam::Error);
  doc = YAML::Load("plugin: x\nmodel: m\nmode: fast\n");
  EXPECT_THROW(beslam::pipeline::validateSettings(doc, fields, "backend", file, "/base", {"plugin"}), beslam::Error);
}

TEST_F(PipelineSpecTest, DatasetPlaceholdersFollowOverrides) {
  const std::string text =
      std::string(kGood) + "detector: {plugin: d, path: \"${dataset.root}/det/${dataset.sequence}.txt\"}\n";
  const auto spec = loadPipeline(write(text), {"dataset.sequence=0007", "dataset.root=/data/tracking"});
  EXPECT_EQ(spec.slots.at("detector").settings["path"].as<std::string>(), "/data/tracking/det/0007.txt");
  EXPECT_EQ(spec.dataset.root, "/data/tracking");
  expectError(std::string(kGood) + "detector: {plugin: d, path: \"${dataset.nope}\"}\n",
              {"pipeline.yaml:9: detector.path: unknown placeholder ${dataset.nope}"});
  expectError(std::string(kGood) + "detector: {plugin: d, path: \"${dataset.root\"}\n",
              {"detector.path: unterminated placeholder"});
}

TEST_F(PipelineSpecTest, BlackFramesAreParsedAndBadOnesNameTheFileAndKey) {
  const auto spec = loadPipeline(write(kGood), {"dataset.black_frames=520-539,600"});
  ASSERT_EQ(spec.dataset.black_frames.size(), 2u);
  EXPECT_EQ(spec.dataset.black_frames[0].first, 520);
  EXPECT_EQ(spec.dataset.black_frames[0].last, 539);
  EXPECT_EQ(spec.dataset.black_frames[1].first, 600);
  EXPECT_TRUE(loadPipeline(write(kGood)).dataset.black_frames.empty());
  const std::string path = (dir_ / "pipeline.yaml").string();
  expectError(
      "dataset:\n  type: kitti_odometry\n  root: data\n  sequence: \"06\"\n  black_frames: 539-520\n"
      "backend: {plugin: backend_pose_replay, poses: poses.txt}\n",
      {path + ":5: dataset.black_frames: range 539-520 ends before it starts"});
  expectError(kGood, {path, "dataset.black_frames", "'x' is not a frame number"}, {"dataset.black_frames=x"});
  expectError(kGood, {path, "dataset.black_frames", "does not come after"}, {"dataset.black_frames=10-20,15"});
}

// Probe: `--set backend.plugin=/tmp/x/trav` (or ../../ traversal) used to become a file path the registry
// loaded. An id is [a-z0-9_]+, checked here with the key and line, before any path is formed.
TEST_F(PipelineSpecTest, PluginIdsThatAreNotIdsNameTheKey) {
  expectError(kGood, {"pipeline.yaml (--set): backend.plugin: '/tmp/x/trav' is not a plugin id (accepted: [a-z0-9_]+"},
              {"backend.plugin=/tmp/x/trav"});
  expectError(kGood, {"backend.plugin: '../../../../tmp/x/trav' is not a plugin id"},
              {"backend.plugin=../../../../tmp/x/trav"});
  expectError(std::string(kGood) + "detector: {plugin: Detector-Image}\n",
              {"pipeline.yaml:9: detector.plugin: 'Detector-Image' is not a plugin id"});
  EXPECT_NO_THROW(loadPipeline(write(std::string(kGood) + "detector: {plugin: none}\n")));
}

// Probe: `features: 20000` then `features: 100` kept the first silently (and both in pipeline.resolved.yaml).
TEST_F(PipelineSpecTest, DuplicateKeysNameBothLines) {
  expectError(std::string(kGood) + "  poses: other.txt\n", {"pipeline.yaml:9: duplicate key 'poses' (first at line 8"});
}

// Probes: a 1.2 KB alias bomb hung the loader; 100,000-deep nesting said only "bad file".
TEST_F(PipelineSpecTest, AliasBombsAndDeepNestingAreOneError) {
  std::string bomb = std::string(kGood) + "description: &a [x, x, x, x, x, x, x, x, x]\n";
  std::string previous = "a";
  for (const char* name : {"b", "c", "d", "e", "f", "g", "h", "i"}) {
    bomb += std::string("x") + name + ": &" + name + " [";
    for (int k = 0; k < 9; ++k) bomb += std::string(k ? ", " : "") + "*" + previous;
    bomb += "]\n";
    previous = name;
  }
  expectError(bomb, {"pipeline.yaml:", "nodes once its aliases (*name) are expanded"});
  expectError(std::string(kGood) + "description: " + std::string(100000, '[') + std::string(100000, ']') + "\n",
              {"pipeline.yaml:9: nested deeper than 64 levels"});
}
