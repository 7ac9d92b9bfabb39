// Map reuse on the rendered corridor: a map saved and loaded is the same map (saving it again gives the
// same bytes), it localises and tracks the sequence's frames to the poses of the run that made it, and
// localisation-only tracking leaves it unchanged. A corrupt, truncated, wrong-version or wrong-camera
// file is refused with one error naming the file; a failed save keeps the old file. A whole run frees
// the keyframes and map points it culls.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string>
#include <unordered_set>

#include "beslam_orb/orb_slam.hpp"
#include "features/orb_extractor.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"
#include "map_io/map_file.hpp"
#include "mapping/local_mapper.hpp"
#include "synthetic_world.hpp"
#include "tracking/tracker.hpp"

namespace beslam::orb {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 40;

Options smallOptions() {
  Options o;
  o.extractor.features = 1000;
  return o;
}

const std::vector<cv::Mat>& corridorImages() {
  static const std::vector<cv::Mat> images = [] {
    const test::CorridorWorld world;
    std::vector<cv::Mat> out;
    for (int i = 0; i < kFrames; ++i) out.push_back(world.render(i));
    return out;
  }();
  return images;
}

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

class MapFileTest : public ::testing::Test {
 protected:
  // One mapping run over the corridor, saved once for every test.
  static void SetUpTestSuite() {
    dir_ = new std::string((fs::temp_directory_path() / ("beslam_map_io_" + std::to_string(::getpid()))).string());
    fs::create_directories(*dir_);
    OrbSlam slam(test::CorridorWorld().camera(), smallOptions());
    for (int i = 0; i < kFrames; ++i) slam.track(corridorImages()[i], cv::Mat(), 0.1 * i, i);
    slam.finish();
    trajectory_ = new std::vector<FramePose>(slam.trajectory());
    stats_ = new Statistics(slam.statistics());
    slam.saveMap(path("map.bin"));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete trajectory_;
    delete stats_;
  }
  static std::string path(const std::string& name) { return (fs::path(*dir_) / name).string(); }

  // `slam` holds the saved map unchanged: its keyframes and map points, and saved as `name` the same bytes.
  static void expectTheSavedMap(OrbSlam& slam, const std::string& name) {
    const Statistics s = slam.statistics();
    EXPECT_EQ(s.keyframes, stats_->keyframes);
    EXPECT_EQ(s.map_points, stats_->map_points);
    slam.saveMap(path(name));
    EXPECT_EQ(readBytes(path(name)), readBytes(path("map.bin")));
  }

  // The runtime_error message loading `file` with `camera` gives ("" if it loads).
  static std::string loadError(const std::string& file, const Camera& camera = test::CorridorWorld().camera()) {
    try {
      Options o = smallOptions();
      o.map_reuse.load_map = file;
      OrbSlam slam(camera, o);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }

  static std::string* dir_;
  static std::vector<FramePose>* trajectory_;
  static Statistics* stats_;
};

std::string* MapFileTest::dir_ = nullptr;
std::vector<FramePose>* MapFileTest::trajectory_ = nullptr;
Statistics* MapFileTest::stats_ = nullptr;

TEST_F(MapFileTest, SavedAndLoadedMapIsTheSameMap) {
  ASSERT_GT(stats_->keyframes, 5);
  OrbSlam loaded(test::CorridorWorld().camera(), smallOptions());
  loaded.loadMap(path("map.bin"));
  expectTheSavedMap(loaded, "again.bin");
}

TEST_F(MapFileTest, LoadedMapTracksTheSameFramesToTheSamePosesWithoutChangingIt) {
  Options o = smallOptions();
  o.map_reuse.load_map = path("map.bin");
  o.map_reuse.localisation_only = true;
  OrbSlam slam(test::CorridorWorld().camera(), o);
  int tracked = 0;
  for (int i = 0; i < kFrames; ++i) {
    const TrackResult r = slam.track(corridorImages()[i], cv::Mat(), 0.1 * i, i);
    EXPECT_FALSE(r.is_keyframe);
    tracked += r.state == TrackingState::Ok;
  }
  slam.finish();
  EXPECT_EQ(tracked, kFrames);  // localised from the first frame on
  expectTheSavedMap(slam, "after_localisation.bin");
  // Every frame the mapping run tracked lands where that run (after its last BA) put it, within the noise of
  // two estimates (online tracking then, localisation against the final map now). The map's unit is the
  // first keyframes' median depth (about 7 m here; the corridor moves 0.4 m = 0.056 units per frame).
  const std::vector<FramePose> poses = slam.trajectory();
  std::vector<double> dts;
  for (const FramePose& ref : *trajectory_)
    for (const FramePose& p : poses)
      if (p.frame_index == ref.frame_index) {
        const double dt = (p.T_world_cam.translation() - ref.T_world_cam.translation()).norm();
        const double da = Eigen::AngleAxisd(p.T_world_cam.linear().transpose() * ref.T_world_cam.linear()).angle();
        EXPECT_LT(dt, 0.01) << "frame " << p.frame_index;
        EXPECT_LT(da * 180 / M_PI, 0.4) << "frame " << p.frame_index;
        dts.push_back(dt);
      }
  ASSERT_EQ(dts.size(), trajectory_->size());
  std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
  EXPECT_LT(dts[dts.size() / 2], 0.002);
}

TEST_F(MapFileTest, SaveMapOptionSavesInFinish) {
  Options o = smallOptions();
  o.map_reuse.load_map = path("map.bin");
  o.map_reuse.localisation_only = true;
  o.map_reuse.save_map = path("finish.bin");
  OrbSlam slam(test::CorridorWorld().camera(), o);
  slam.track(corridorImages()[3], cv::Mat(), 0.3, 3);
  slam.finish();
  EXPECT_EQ(readBytes(path("finish.bin")), readBytes(path("map.bin")));
}

void expectOneError(const std::string& message, const std::string& file, const std::string& problem) {
  EXPECT_NE(message.find("map file '" + file + "'"), std::string::npos) << message;
  EXPECT_NE(message.find(problem), std::string::npos) << message;
}

TEST_F(MapFileTest, CorruptFileIsRefused) {
  std::string bytes = readBytes(path("map.bin"));
  bytes[bytes.size() / 2] ^= 0x5a;
  writeBytes(path("corrupt.bin"), bytes);
  expectOneError(loadError(path("corrupt.bin")), path("corrupt.bin"), "corrupt: checksum mismatch");
  writeBytes(path("text.bin"), "dataset: {type: synth}\n");
  expectOneError(loadError(path("text.bin")), path("text.bin"), "not a BE-SLAM map file");
  expectOneError(loadError(path("missing.bin")), path("missing.bin"), "cannot open");
}

// Found by the map_file fuzz target (tests/fuzz/corpus/map_file/found-keypoint-outside-image.map): a keypoint
// at x = -2.8e24 loaded, and the feature grid's cell index overflowed int (undefined behaviour). A keypoint
// outside the map's image is now the file's error.
TEST(MapFile, AKeypointOutsideTheImageIsRefused) {
  const std::string found = BESLAM_SOURCE_DIR "/tests/fuzz/corpus/map_file/found-keypoint-outside-image.map";
  MapFileInfo expected;  // the fuzz target's camera and pyramid
  expected.camera = Camera{160, 120, 100, 100, 80, 60};
  expected.levels = 3;
  expected.scale_factor = 1.2;
  const ScalePyramid pyramid(3, 1.2);
  for (const std::string name : {"found-keypoint-outside-image.map", "two-keyframes.map"}) {
    const std::string file = BESLAM_SOURCE_DIR "/tests/fuzz/corpus/map_file/" + name;
    Map map;
    std::vector<ObjectLandmark> landmarks;
    try {
      loadMapFile(file, expected, pyramid, map, landmarks);
      EXPECT_EQ(file, BESLAM_SOURCE_DIR "/tests/fuzz/corpus/map_file/two-keyframes.map") << "loaded";
      EXPECT_EQ(map.numKeyFrames(), 2u);
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(file, found) << e.what();
      expectOneError(e.what(), found, "outside the 160x120 image");
      EXPECT_EQ(map.numKeyFrames(), 0u);
    }
  }
}

TEST_F(MapFileTest, TruncatedFileIsRefused) {
  const std::string bytes = readBytes(path("map.bin"));
  for (size_t keep : {bytes.size() - 1, bytes.size() / 3, size_t{14}}) {
    writeBytes(path("truncated.bin"), bytes.substr(0, keep));
    expectOneError(loadError(path("truncated.bin")), path("truncated.bin"), "truncated");
  }
}

TEST_F(MapFileTest, OtherFormatVersionIsRefused) {
  std::string bytes = readBytes(path("map.bin"));
  bytes[8] = 4;  // the u32 version after the 8-byte magic
  writeBytes(path("v4.bin"), bytes);
  expectOneError(loadError(path("v4.bin")), path("v4.bin"), "format version 4; this build reads versions 1 to 3");
}

// Loop edges (the essential graph's, which keep their keyframes from culling) are saved and loaded.
TEST_F(MapFileTest, LoopEdgesAreSavedAndLoaded) {
  const Camera camera = test::CorridorWorld().camera();
  const Options o = smallOptions();
  const OrbExtractor extractor(o.extractor);
  MapFileInfo info;
  info.camera = camera;
  info.levels = o.extractor.levels;
  info.scale_factor = o.extractor.scale_factor;
  auto load = [&](const std::string& file, Map& map) {
    std::vector<ObjectLandmark> landmarks;
    loadMapFile(file, info, extractor.pyramid(), map, landmarks);
  };
  Map map;
  load(path("map.bin"), map);
  ASSERT_GT(map.numKeyFrames(), 3u);
  KeyFrame* first = *map.keyframes().begin();
  KeyFrame* last = *map.keyframes().rbegin();
  for (const KeyFrame* kf : map.keyframes()) EXPECT_TRUE(kf->loop_edges.empty());
  first->loop_edges.insert(last);
  last->loop_edges.insert(first);
  saveMapFile(path("loop.bin"), map, info, {});
  Map again;
  load(path("loop.bin"), again);
  std::map<long, std::vector<long>> edges;
  for (const KeyFrame* kf : again.keyframes())
    for (const KeyFrame* other : kf->loop_edges) edges[kf->id].push_back(other->id);
  EXPECT_EQ(edges, (std::map<long, std::vector<long>>{{first->id, {last->id}}, {last->id, {first->id}}}));
}

TEST_F(MapFileTest, OtherCameraIsRefused) {
  Camera c = test::CorridorWorld().camera();
  c.fx += 1;
  expectOneError(loadError(path("map.bin"), c), path("map.bin"), "made with camera 640x480 fx 500");
  c = test::CorridorWorld().camera();
  c.width = 800;
  expectOneError(loadError(path("map.bin"), c), path("map.bin"), "this run's camera is 800x480");
}

TEST_F(MapFileTest, FailedSaveKeepsTheOldFile) {
  const std::string target = path("kept.bin");
  writeBytes(target, "the old map");
  // The temporary file's place is taken by a folder: the write fails before anything touches the target.
  const std::string tmp = target + ".tmp." + std::to_string(::getpid());
  fs::create_directories(tmp);
  OrbSlam loaded(test::CorridorWorld().camera(), smallOptions());
  loaded.loadMap(path("map.bin"));
  try {
    loaded.saveMap(target);
    ADD_FAILURE() << "saving over a blocked temporary file succeeded";
  } catch (const std::runtime_error& e) {
    expectOneError(e.what(), target, "cannot create the temporary file");
  }
  EXPECT_EQ(readBytes(target), "the old map");
  fs::remove_all(tmp);
  loaded.saveMap(target);  // and with the way clear, the save replaces it
  EXPECT_EQ(readBytes(target), readBytes(path("map.bin")));
  EXPECT_FALSE(fs::exists(tmp));
}

TEST_F(MapFileTest, LoadingAfterTrackingIsALogicError) {
  OrbSlam slam(test::CorridorWorld().camera(), smallOptions());
  slam.track(corridorImages()[0], cv::Mat(), 0, 0);
  EXPECT_THROW(slam.loadMap(path("map.bin")), std::logic_error);
}

// The tracker's side of freeing: a keyframe that trajectory records and the local map point at is culled
// and freed; the records follow its parent with unchanged poses and tracking goes on. (Keyframe
// culling rarely fires on these sequences, so the culling is forced here.)
TEST(MapMemory, TrackerLetsGoOfACulledKeyFrame) {
  const Camera cam = test::CorridorWorld().camera();
  Options o = smallOptions();
  const OrbExtractor extractor(o.extractor);
  Map map;
  LocalMapper mapper(map, cam, extractor.pyramid(), o.mapping, o.scale, o.object_landmarks, o.static_object_weight);
  std::vector<std::pair<KeyFrame*, bool>> jobs;
  Tracker tracker(
      cam, TrackerOptions(o), extractor.pyramid(), map,
      [&](KeyFrame* kf, bool initial) { jobs.emplace_back(kf, initial); }, [&] { mapper.reset(); });
  auto track = [&](int i) {
    const int budget = tracker.initialising() ? o.extractor.features * o.init.features_factor : o.extractor.features;
    const TrackResult r = tracker.track(extractor.extract(corridorImages()[i], cv::Mat(), budget), 0.1 * i, i);
    for (auto& [kf, initial] : jobs) mapper.processKeyFrame(kf, !initial);
    jobs.clear();
    return r.state;
  };
  for (int i = 0; i < 25; ++i) track(i);
  ASSERT_GE(map.numKeyFrames(), 5u);
  auto composed = [](const FrameRecord& r) {
    Eigen::Isometry3d T_c_ref = r.T_c_ref;
    const KeyFrame* ref = r.reference;
    while (ref->bad) {
      T_c_ref = T_c_ref * ref->T_cp;
      ref = ref->parent;
    }
    return T_c_ref * ref->T_cw;
  };
  // The earliest keyframe after the origin that records are referenced to: culled (a recent one would take
  // the points the current frames track with it).
  KeyFrame* doomed = nullptr;
  for (const FrameRecord& r : tracker.records())
    if (r.reference != map.origin() && (!doomed || r.reference->id < doomed->id)) doomed = r.reference;
  ASSERT_NE(doomed, nullptr);
  std::vector<Eigen::Isometry3d> before;
  for (const FrameRecord& r : tracker.records()) before.push_back(composed(r));
  const long kfs_before = KeyFrame::instances();
  doomed->setBad();
  tracker.forgetCulled();
  mapper.forgetCulled();
  map.releaseCulled();
  EXPECT_EQ(KeyFrame::instances(), kfs_before - 1);
  const std::unordered_set<const KeyFrame*> live(map.keyframes().begin(), map.keyframes().end());
  ASSERT_EQ(tracker.records().size(), before.size());
  for (size_t k = 0; k < before.size(); ++k) {
    const FrameRecord& r = tracker.records()[k];
    ASSERT_TRUE(live.count(r.reference)) << "record of frame " << r.index;
    EXPECT_TRUE(composed(r).isApprox(before[k], 1e-9)) << "frame " << r.index;
  }
  ASSERT_TRUE(tracker.lastKeyFrame() == nullptr || live.count(tracker.lastKeyFrame()));
  for (int i = 25; i < kFrames; ++i) EXPECT_EQ(track(i), TrackingState::Ok) << "frame " << i;
}

// A whole run: what culling removed is freed (allocated objects = live ones), and so is everything with
// the OrbSlam.
TEST(MapMemory, CulledKeyFramesAndPointsAreFreedDuringARun) {
  const long kfs_before = KeyFrame::instances(), points_before = MapPoint::instances();
  {
    Options o = smallOptions();
    OrbSlam slam(test::CorridorWorld().camera(), o);
    for (int i = 0; i < kFrames; ++i) slam.track(corridorImages()[i], cv::Mat(), 0.1 * i, i);
    slam.finish();
    const Statistics s = slam.statistics();
    EXPECT_GT(s.map_points, 100);
    EXPECT_EQ(KeyFrame::instances() - kfs_before, s.keyframes);
    EXPECT_EQ(MapPoint::instances() - points_before, s.map_points);
    // The trajectory composes through re-anchored records, never through a freed keyframe.
    EXPECT_GE(static_cast<int>(slam.trajectory().size()), kFrames - s.initialised_at_frame);
  }
  EXPECT_EQ(KeyFrame::instances(), kfs_before);
  EXPECT_EQ(MapPoint::instances(), points_before);
}

}  // namespace
}  // namespace beslam::orb
