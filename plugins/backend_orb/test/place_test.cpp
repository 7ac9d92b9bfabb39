// Place recognition on the rendered corridor: vocabulary training is deterministic and round-trips
// through its file, damaged files give one clear error, BoW scores rank the view of the same place
// first, and tracking lost in a blackout relocalises by bag of words when the images return.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "beslam/formats/align.hpp"
#include "beslam/test/error_text.hpp"
#include "beslam_orb/orb_slam.hpp"
#include "features/orb_extractor.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map_io/map_file.hpp"
#include "place/keyframe_database.hpp"
#include "place/vocabulary.hpp"
#include "synthetic_world.hpp"
#include "tracking/tracker.hpp"

namespace beslam::orb {
namespace {

using place::BowVector;
using place::Vocabulary;

constexpr int kFrames = 40;

const std::vector<cv::Mat>& corridorImages() {
  static const test::CorridorWorld world;
  static std::vector<cv::Mat> images;
  if (images.empty())
    for (int i = 0; i < kFrames; ++i) images.push_back(world.render(i));
  return images;
}

cv::Mat describe(const cv::Mat& image, int features = 1000) {
  ExtractorOptions eo;
  eo.features = features;
  return OrbExtractor(eo).extract(image, cv::Mat())->descriptors;
}

// Trained on the odd frames (the tests query even ones).
std::vector<cv::Mat> trainingDescriptors() {
  std::vector<cv::Mat> out;
  for (int i = 1; i < kFrames; i += 2) out.push_back(describe(corridorImages()[i], 500));
  return out;
}

std::string readAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void writeAll(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string tempPath(const std::string& name) { return ::testing::TempDir() + "beslam_place_" + name; }

// The error load() throws for a file, or "" when it loads.
std::string loadError(const std::string& path) {
  return beslam::test::errorText<std::runtime_error>([&] { Vocabulary::load(path); });
}

TEST(Vocabulary, SameSeedGivesAByteIdenticalFile) {
  place::VocabularyTrainOptions options;
  options.k = 6;
  options.levels = 4;
  options.seed = 3;
  const auto descriptors = trainingDescriptors();
  Vocabulary::train(descriptors, options).save(tempPath("a.bvoc"));
  Vocabulary::train(descriptors, options).save(tempPath("b.bvoc"));
  const std::string a = readAll(tempPath("a.bvoc")), b = readAll(tempPath("b.bvoc"));
  ASSERT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
  options.seed = 4;
  Vocabulary::train(descriptors, options).save(tempPath("c.bvoc"));
  EXPECT_NE(a, readAll(tempPath("c.bvoc")));
}

TEST(Vocabulary, SaveLoadRoundTripGivesTheSameWordsAndVectors) {
  place::VocabularyTrainOptions options;
  options.seed = 1;
  const Vocabulary trained = Vocabulary::train(trainingDescriptors(), options);
  EXPECT_EQ(trained.k(), 10);
  EXPECT_EQ(trained.levels(), 6);
  EXPECT_GT(trained.numWords(), 500u);
  trained.save(tempPath("round.bvoc"));
  const Vocabulary loaded = Vocabulary::load(tempPath("round.bvoc"));
  EXPECT_EQ(loaded.numNodes(), trained.numNodes());
  EXPECT_EQ(loaded.numWords(), trained.numWords());
  const cv::Mat d = describe(corridorImages()[10]);
  BowVector b1, b2;
  place::FeatureVector f1, f2;
  trained.transform(d, b1, &f1, 4);
  loaded.transform(d, b2, &f2, 4);
  EXPECT_EQ(b1, b2);
  EXPECT_EQ(f1, f2);
  ASSERT_FALSE(b1.empty());
  float sum = 0;
  for (const auto& [w, v] : b1) sum += v;
  EXPECT_NEAR(sum, 1.0f, 1e-4f);  // L1-normalised
  EXPECT_NEAR(Vocabulary::score(b1, b1), 1.0, 1e-6);
  size_t in_index = 0;
  for (const auto& [node, features] : f1) in_index += features.size();
  EXPECT_EQ(in_index, static_cast<size_t>(d.rows));  // every feature in the direct index once
  // Saving leaves no temporary file behind and overwrites atomically.
  trained.save(tempPath("round.bvoc"));
  EXPECT_EQ(readAll(tempPath("round.bvoc")).size(), readAll(tempPath("round.bvoc")).size());
}

TEST(Vocabulary, DamagedFilesGiveOneClearErrorNamingTheFile) {
  place::VocabularyTrainOptions options;
  options.k = 5;
  options.levels = 3;
  Vocabulary::train(trainingDescriptors(), options).save(tempPath("good.bvoc"));
  const std::string good = readAll(tempPath("good.bvoc"));
  EXPECT_EQ(loadError(tempPath("good.bvoc")), "");

  // Each damaged copy: its bytes, what the error must say, and whether it names the file.
  const auto with = [&](size_t at, char value) {
    std::string bytes = good;
    bytes[at] = value;
    return bytes;
  };
  const struct {
    const char* name;
    std::string bytes;
    const char* says;
    bool names_file;
  } damaged[] = {
      {"truncated.bvoc", good.substr(0, good.size() - 100), "truncated", true},
      {"header.bvoc", good.substr(0, 12), "truncated", false},
      {"magic.bvoc", with(0, 'X'), "magic", true},
      {"version.bvoc", with(8, 7), "version 7", true},  // format version 7
      {"corrupt.bvoc", with(good.size() / 2, static_cast<char>(good[good.size() / 2] ^ 0x10)), "checksum", false},
  };
  for (const auto& d : damaged) {
    const std::string path = tempPath(d.name);
    writeAll(path, d.bytes);
    const std::string e = loadError(path);
    if (d.names_file) {
      EXPECT_NE(e.find(path), std::string::npos) << e;
    }
    EXPECT_NE(e.find(d.says), std::string::npos) << e;
  }

  const std::string e = loadError(tempPath("missing.bvoc"));
  EXPECT_NE(e.find("missing.bvoc"), std::string::npos) << e;
}

// Found by the vocabulary fuzz target (tests/fuzz/corpus/vocabulary/found-weight-not-an-idf.bvoc): a file
// whose checksum fits but whose word weights are no idf (7.6e7 here; an infinite one would make every bag of
// words holding it NaN) loaded without a word. Now one error naming the file and the node.
TEST(VocabularyFile, AWeightThatIsNotAnIdfIsRefused) {
  const std::string found = BESLAM_SOURCE_DIR "/tests/fuzz/corpus/vocabulary/found-weight-not-an-idf.bvoc";
  const std::string e = loadError(found);
  EXPECT_NE(e.find(found + ": not a usable ORB vocabulary: node 14 has weight 75716800"), std::string::npos) << e;
  EXPECT_NE(e.find("not an idf in [0, 100]"), std::string::npos) << e;
  // The seeds the fuzz target trained from the shipped vocabulary load.
  EXPECT_EQ(loadError(BESLAM_SOURCE_DIR "/tests/fuzz/corpus/vocabulary/k3-l2.bvoc"), "");
}

TEST(Vocabulary, ScoresRankTheViewOfTheSamePlaceFirst) {
  const Vocabulary vocabulary = Vocabulary::train(trainingDescriptors(), {});
  // Database: every 6th frame (0, 6, ..., 36); queries: the frames one step further on (0.4 m later),
  // which revisit their database frame's place.
  std::vector<BowVector> database;
  for (int i = 0; i < kFrames; i += 6) {
    database.emplace_back();
    vocabulary.transform(describe(corridorImages()[i]), database.back());
  }
  for (int q = 1; q < kFrames; q += 6) {
    BowVector query;
    vocabulary.transform(describe(corridorImages()[q]), query);
    size_t best = 0;
    double best_score = -1, second = -1;
    for (size_t j = 0; j < database.size(); ++j) {
      const double s = Vocabulary::score(query, database[j]);
      if (s > best_score) {
        second = best_score;
        best_score = s;
        best = j;
      } else if (s > second) {
        second = s;
      }
    }
    EXPECT_EQ(static_cast<int>(best) * 6, q - 1) << "query " << q;
    EXPECT_GT(best_score, second) << "query " << q;
  }
}

// The inverted index: shared words per keyframe, erase, culled keyframes passed over, and the candidate
// with the most similar vector first.
TEST(KeyFrameDatabase, FindsKeyFramesSharingWordsAndForgetsErasedOnes) {
  Map map;
  const ScalePyramid pyramid(8, 1.2);
  const Camera camera{640, 480, 500, 500, 320, 240};
  auto features = std::make_shared<FeatureSet>();
  auto keyframe = [&](const BowVector& bow) {
    Frame f(0, 0.0, features);
    f.bow = bow;
    return map.createKeyFrame(f, camera, pyramid);
  };
  KeyFrame* a = keyframe({{1, 0.5f}, {2, 0.5f}});
  KeyFrame* b = keyframe({{2, 0.25f}, {3, 0.75f}});
  KeyFrame* c = keyframe({{4, 1.0f}});
  KeyFrameDatabase db;
  for (KeyFrame* kf : {a, b, c}) db.add(kf);
  const BowVector query{{2, 0.3f}, {3, 0.7f}};
  auto shared = db.sharedWords(query);
  ASSERT_EQ(shared.size(), 2u);
  EXPECT_EQ(shared[0].first, a);
  EXPECT_EQ(shared[0].second, 1);
  EXPECT_EQ(shared[1].first, b);
  EXPECT_EQ(shared[1].second, 2);
  const auto candidates = db.relocalisationCandidates(query);
  ASSERT_FALSE(candidates.empty());
  EXPECT_EQ(candidates.front(), b);
  db.erase(b);
  shared = db.sharedWords(query);
  ASSERT_EQ(shared.size(), 1u);
  EXPECT_EQ(shared[0].first, a);
  a->bad = true;
  EXPECT_TRUE(db.sharedWords(query).empty());
  a->bad = false;
  // A keyframe added after an erase takes the freed slot (b's, before c's): it is counted for its own words
  // only, and the result stays in id order (a, c, d), not in slot order (a, d, c).
  KeyFrame* d = keyframe({{1, 0.2f}, {3, 0.3f}, {5, 0.5f}});
  db.add(d);
  db.add(d);  // indexed once
  const BowVector query2{{1, 0.4f}, {3, 0.4f}, {4, 0.2f}};
  shared = db.sharedWords(query2);
  ASSERT_EQ(shared.size(), 3u);
  EXPECT_EQ(shared[0].first, a);
  EXPECT_EQ(shared[0].second, 1);
  EXPECT_EQ(shared[1].first, c);
  EXPECT_EQ(shared[1].second, 1);
  EXPECT_EQ(shared[2].first, d);
  EXPECT_EQ(shared[2].second, 2);
  db.erase(b);  // not indexed any more: nothing happens
  EXPECT_EQ(db.sharedWords(query2).size(), 3u);
  db.clear();
  EXPECT_TRUE(db.sharedWords({{4, 1.0f}}).empty());
}

// Backend options (1000 features) with a vocabulary trained on the corridor, saved as `name`.
Options withCorridorVocabulary(const std::string& name) {
  place::VocabularyTrainOptions vo;
  vo.seed = 1;
  Vocabulary::train(trainingDescriptors(), vo).save(tempPath(name));
  Options options;
  options.extractor.features = 1000;
  options.vocabulary = tempPath(name);
  return options;
}

// Tracking lost in 5 black frames relocalises by bag of words within 3 frames of the images returning,
// at the true pose (Sim(3)-aligned to the truth on the frames before the blackout). After the blackout
// the camera is back at a place it mapped 4-5 m earlier (a revisit, as on a second lap), so the last
// pose's neighbourhood does not help: only the keyframe database can find it.
TEST(Relocalisation, ResumesAfterABlackout) {
  const Options options = withCorridorVocabulary("reloc.bvoc");
  const test::CorridorWorld world;
  OrbSlam slam(world.camera(), options);
  // Frame k shows corridor view view[k]; -1 = black.
  std::vector<int> view;
  for (int i = 0; i < 24; ++i) view.push_back(i);
  for (int i = 0; i < 5; ++i) view.push_back(-1);
  const int back_at = static_cast<int>(view.size());
  for (int i = 12; i < 22; ++i) view.push_back(i);
  const cv::Mat black = cv::Mat::zeros(corridorImages()[0].size(), CV_8UC1);
  int64_t resumed_at = -1;
  bool relocalised_flag = false;
  for (int k = 0; k < static_cast<int>(view.size()); ++k) {
    const TrackResult r = slam.track(view[k] < 0 ? black : corridorImages()[view[k]], cv::Mat(), 0.1 * k, k);
    if (view[k] < 0) {
      EXPECT_NE(r.state, TrackingState::Ok) << "frame " << k;
    }
    if (k >= back_at && resumed_at < 0 && r.state == TrackingState::Ok) {
      resumed_at = k;
      relocalised_flag = r.relocalised;
    }
  }
  slam.finish();
  const Statistics stats = slam.statistics();
  EXPECT_EQ(stats.resets, 0);
  EXPECT_EQ(stats.relocalisations, 1);
  ASSERT_GE(resumed_at, 0) << "never resumed";
  EXPECT_LE(resumed_at, back_at + 2);  // within 3 frames of the images returning
  EXPECT_TRUE(relocalised_flag);
  // Align on the frames before the blackout, then check every frame after it.
  std::vector<Eigen::Vector3d> est, truth;
  std::vector<FramePose> after;
  std::map<int, Eigen::Isometry3d> first_visit;  // view -> its estimate before the blackout
  for (const FramePose& p : slam.onlineTrajectory()) {
    const int v = view[static_cast<size_t>(p.frame_index)];
    ASSERT_GE(v, 0) << "a black frame got a pose";
    if (p.frame_index < back_at) {
      est.push_back(p.T_world_cam.translation());
      truth.push_back(world.pose(v).translation());
      first_visit[v] = p.T_world_cam;
    } else {
      after.push_back(p);
    }
  }
  ASSERT_GE(est.size(), 10u);
  ASSERT_GE(after.size(), 5u);
  const auto sim3 = formats::umeyama(truth, est, est.size(), true);
  for (const FramePose& p : after) {
    const int v = view[static_cast<size_t>(p.frame_index)];
    const Eigen::Vector3d aligned = sim3.apply(p.T_world_cam.translation());
    EXPECT_LT((aligned - world.pose(v).translation()).norm(), 0.10) << "frame " << p.frame_index;  // 9 m mapped
    // The same image seen before the blackout: the same orientation (positions along a nearly straight
    // path leave the alignment's roll loose, so orientation is compared within the map).
    ASSERT_TRUE(first_visit.count(v)) << "view " << v;
    const Eigen::Matrix3d dR = first_visit[v].linear().transpose() * p.T_world_cam.linear();
    EXPECT_LT(Eigen::AngleAxisd(dR).angle(), 1.0 * M_PI / 180) << "frame " << p.frame_index;
  }
}

// A map file keeps descriptors, not words: the keyframes of a loaded map join the keyframe database with
// the current vocabulary's words, so a frame from anywhere in the map finds its place by bag of words.
TEST(Relocalisation, ALoadedMapsKeyFramesAreFoundByBagOfWords) {
  const Options options = withCorridorVocabulary("loaded.bvoc");
  const test::CorridorWorld world;
  {
    OrbSlam slam(world.camera(), options);
    for (int i = 0; i < 24; ++i) slam.track(corridorImages()[i], cv::Mat(), 0.1 * i, i);
    slam.finish();
    slam.saveMap(tempPath("loaded.map"));
  }
  const OrbExtractor extractor(options.extractor);
  MapFileInfo expected;
  expected.camera = world.camera();
  expected.levels = options.extractor.levels;
  expected.scale_factor = options.extractor.scale_factor;
  Map map;
  std::vector<ObjectLandmark> landmarks;
  loadMapFile(tempPath("loaded.map"), expected, extractor.pyramid(), map, landmarks);
  ASSERT_GT(map.numKeyFrames(), 5u);
  const Vocabulary vocabulary = Vocabulary::load(tempPath("loaded.bvoc"));
  KeyFrameDatabase database;
  Tracker tracker(
      world.camera(), TrackerOptions(options), extractor.pyramid(), map, [](KeyFrame*, bool) {}, [] {}, &vocabulary,
      &database);
  BowVector bow;
  vocabulary.transform(describe(corridorImages()[16]), bow);
  EXPECT_TRUE(database.relocalisationCandidates(bow).empty()) << "nothing indexed before the map is handed over";
  tracker.mapLoaded();
  const std::vector<KeyFrame*> candidates = database.relocalisationCandidates(bow);
  ASSERT_FALSE(candidates.empty());
  EXPECT_LE(std::abs(candidates.front()->frame_index - 16), 3)
      << "keyframe of frame " << candidates.front()->frame_index;
  for (KeyFrame* kf : map.keyframes()) EXPECT_FALSE(kf->bow.empty()) << "keyframe " << kf->id;
}

TEST(Relocalisation, WithoutAVocabularyTheBackendStillTracks) {
  Options options;
  options.extractor.features = 1000;
  options.vocabulary = "";
  const test::CorridorWorld world;
  OrbSlam slam(world.camera(), options);
  int ok = 0;
  for (int i = 0; i < 20; ++i) ok += slam.track(corridorImages()[i], cv::Mat(), 0.1 * i, i).state == TrackingState::Ok;
  EXPECT_GE(ok, 15);
  options.vocabulary = tempPath("does_not_exist.bvoc");
  EXPECT_THROW(OrbSlam(world.camera(), options), std::runtime_error);
}

}  // namespace
}  // namespace beslam::orb
