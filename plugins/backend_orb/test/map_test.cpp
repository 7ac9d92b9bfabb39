// Map bookkeeping on a simulated map: covisibility weights, keyframe culling of redundant keyframes
// with spanning-tree re-parenting, point replacement (fusion) and observation erasure, and culled
// objects freed with no pointer to them left in the live map.
#include "map/map.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <thread>
#include <unordered_set>

#include "features/scale_pyramid.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map_point.hpp"
#include "map_builder.hpp"
#include "mapping/local_mapper.hpp"
#include "mapping/map_gate.hpp"

namespace beslam::orb {
namespace {

const Camera kCam{1226, 370, 718.856, 718.856, 607.19, 185.22};

// n keyframes 0.5 m apart, each observing every one of 150 points at level 0.
struct SimMap {
  ScalePyramid pyr{8, 1.2};
  Map map;
  std::vector<KeyFrame*> kfs;
  std::vector<MapPoint*> points;

  explicit SimMap(int n) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> ux(-6, 6), uy(-2, 2), uz(8, 30);
    std::vector<Eigen::Vector3d> pw;
    for (int i = 0; i < 150; ++i) pw.emplace_back(ux(rng), uy(rng), uz(rng));
    std::vector<Eigen::Isometry3d> poses;
    for (int k = 0; k < n; ++k) {
      Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
      T_cw.translation() = Eigen::Vector3d(0, 0, -0.5 * k);
      poses.push_back(T_cw);
    }
    kfs = test::buildMap(map, kCam, pyr, poses, poses, pw, pw, 0.0, 1);
    points.assign(map.points().begin(), map.points().end());  // id order = point order
  }
};

TEST(Map, CovisibilityCountsSharedPoints) {
  SimMap m(4);
  EXPECT_EQ(m.kfs[3]->weight(m.kfs[0]), 150);
  EXPECT_EQ(m.kfs[3]->covisibles().size(), 3u);
  EXPECT_EQ(m.kfs[1]->parent, m.kfs[0]);
  EXPECT_EQ(m.kfs[0]->parent, nullptr);
}

TEST(Map, RedundantKeyFramesAreCulledAndTheTreeStaysConnected) {
  SimMap m(5);
  std::vector<Eigen::Isometry3d> poses;
  for (KeyFrame* kf : m.kfs) poses.push_back(kf->T_cw);
  const Options o{};  // the mapper with the run's defaults (Options' mapping, scale and object modules)
  LocalMapper mapper(m.map, kCam, m.pyr, o.mapping, o.scale, o.object_landmarks, o.static_object_weight);
  // Every point is seen by all five: keyframes 1 and 2 are redundant; after them the points have
  // three observations left, so keyframe 3 is not; the origin and the current keyframe never go.
  EXPECT_EQ(mapper.cullKeyFrames(m.kfs[4]), 2);
  EXPECT_TRUE(m.kfs[1]->bad);
  EXPECT_TRUE(m.kfs[2]->bad);
  EXPECT_FALSE(m.kfs[0]->bad);
  EXPECT_FALSE(m.kfs[3]->bad);
  EXPECT_EQ(m.map.numKeyFrames(), 3u);
  for (KeyFrame* kf : m.map.keyframes()) {
    if (kf == m.map.origin()) continue;
    ASSERT_NE(kf->parent, nullptr);
    EXPECT_FALSE(kf->parent->bad);
  }
  // A culled keyframe's pose is still recoverable through its parent chain.
  for (int k : {1, 2}) {
    KeyFrame* kf = m.kfs[k];
    Eigen::Isometry3d T = kf->T_cp;
    KeyFrame* p = kf->parent;
    while (p->bad) {
      T = T * p->T_cp;
      p = p->parent;
    }
    EXPECT_TRUE((T * p->T_cw).isApprox(poses[k], 1e-9));
  }
  for (MapPoint* mp : m.points) EXPECT_EQ(mp->numObservations(), 3);
}

TEST(Map, ReplacingAPointMovesItsObservations) {
  SimMap m(3);
  MapPoint* a = m.points[0];
  MapPoint* b = m.map.createMapPoint(a->position, m.kfs[0]);
  // b is seen only by keyframe 2 at another keypoint; replacing b by a keeps a's keypoint there.
  m.kfs[2]->addPoint(b, 5);
  b->addObservation(m.kfs[2], 5);
  b->replaceWith(a);
  EXPECT_TRUE(b->bad);
  EXPECT_EQ(b->latest(), a);
  EXPECT_EQ(m.kfs[2]->points[5], nullptr);  // a was already in keyframe 2
  EXPECT_EQ(a->numObservations(), 3);
  // Erasing observations down to two marks the point bad and clears it from every keyframe.
  a->eraseObservation(m.kfs[0]);
  EXPECT_TRUE(a->bad);
  EXPECT_EQ(m.kfs[1]->points[0], nullptr);
}

// Every pointer the live map holds points at a live object (compared by address: nothing is dereferenced
// that may have been freed).
void expectNoCulledReferences(const Map& map) {
  const std::unordered_set<const KeyFrame*> kfs(map.keyframes().begin(), map.keyframes().end());
  const std::unordered_set<const MapPoint*> points(map.points().begin(), map.points().end());
  for (const KeyFrame* kf : map.keyframes()) {
    if (kf != map.origin()) {
      EXPECT_TRUE(kfs.count(kf->parent)) << "keyframe " << kf->id << ": parent";
    }
    for (const KeyFrame* c : kf->children) EXPECT_TRUE(kfs.count(c)) << "keyframe " << kf->id << ": child";
    for (const auto& [other, w] : kf->connections()) EXPECT_TRUE(kfs.count(other)) << "keyframe " << kf->id;
    for (const MapPoint* mp : kf->points) {
      if (mp) {
        EXPECT_TRUE(points.count(mp)) << "keyframe " << kf->id << ": map point";
      }
    }
  }
  for (const MapPoint* mp : map.points()) {
    EXPECT_TRUE(kfs.count(mp->reference)) << "map point " << mp->id << ": reference";
    for (const auto& [kf, idx] : mp->observations) EXPECT_TRUE(kfs.count(kf)) << "map point " << mp->id;
  }
}

TEST(Map, CulledObjectsAreFreed) {
  const long kfs_before = KeyFrame::instances(), points_before = MapPoint::instances();
  {
    SimMap m(5);
    EXPECT_EQ(KeyFrame::instances() - kfs_before, 5);
    EXPECT_EQ(MapPoint::instances() - points_before, 150);
    const Options o{};
    LocalMapper mapper(m.map, kCam, m.pyr, o.mapping, o.scale, o.object_landmarks, o.static_object_weight);
    ASSERT_EQ(mapper.cullKeyFrames(m.kfs[4]), 2);
    // Two of the points lose all but two observations too.
    m.kfs[0]->erasePoint(size_t{0});  // as bundle adjustment drops an outlier: both sides
    m.points[0]->eraseObservation(m.kfs[0]);
    m.points[1]->replaceWith(m.points[2]);
    EXPECT_TRUE(m.points[0]->bad);
    EXPECT_EQ(m.map.allocatedKeyFrames(), 5u);  // flagged, still allocated until released
    EXPECT_EQ(m.map.allocatedPoints(), 150u);
    m.map.releaseCulled();
    EXPECT_EQ(m.map.allocatedKeyFrames(), 3u);
    EXPECT_EQ(m.map.allocatedPoints(), 148u);
    EXPECT_EQ(m.map.numKeyFrames(), 3u);
    EXPECT_EQ(m.map.points().size(), 148u);
    EXPECT_EQ(KeyFrame::instances() - kfs_before, 3);
    EXPECT_EQ(MapPoint::instances() - points_before, 148);
    expectNoCulledReferences(m.map);
    // The live map goes on working: more culling and releasing.
    m.kfs[3]->erasePoint(size_t{3});
    m.points[3]->eraseObservation(m.kfs[3]);
    m.map.releaseCulled();
    EXPECT_EQ(MapPoint::instances() - points_before, 147);
    expectNoCulledReferences(m.map);
    m.map.clear();
    EXPECT_EQ(KeyFrame::instances(), kfs_before);
    EXPECT_EQ(MapPoint::instances(), points_before);
  }
  EXPECT_EQ(KeyFrame::instances(), kfs_before);
  EXPECT_EQ(MapPoint::instances(), points_before);
}

// Concurrent mapping's gate: never two holders, and a tracker that waits gets in at the mapper's next safe
// point (it would wait forever otherwise: the mapper never leaves until the tracker is done).
TEST(MapGate, OneHolderAtATimeAndTheTrackerGetsInAtSafePoints) {
  MapGate gate;
  std::atomic<int> inside{0};
  std::atomic<bool> tracker_done{false};
  std::atomic<bool> mapper_in{false};
  int tracker_turns = 0;
  std::thread mapper([&] {
    gate.enterMapper();
    mapper_in = true;
    while (!tracker_done) {  // a step, then a safe point
      EXPECT_EQ(inside.fetch_add(1), 0);
      inside.fetch_sub(1);
      gate.yieldToTracker();
    }
    gate.leaveMapper();
  });
  while (!mapper_in) std::this_thread::yield();  // the mapper holds the gate before the tracker asks
  for (int i = 0; i < 200; ++i) {
    gate.enterTracker();
    EXPECT_EQ(inside.fetch_add(1), 0);
    ++tracker_turns;
    inside.fetch_sub(1);
    gate.leaveTracker();
  }
  tracker_done = true;
  mapper.join();
  EXPECT_EQ(tracker_turns, 200);
  gate.enterTracker();  // and the gate is free again
  gate.leaveTracker();
}

}  // namespace
}  // namespace beslam::orb
