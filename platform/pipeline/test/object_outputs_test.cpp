// Objects follow the keyframe they were fitted from when a loop correction later moves it.
#include "object_outputs.hpp"

#include <gtest/gtest.h>

namespace beslam::pipeline::detail {
namespace {

registry::ObjectLandmark car(int32_t track_id, const Eigen::Vector3d& p_world) {
  registry::ObjectLandmark l;
  l.track_id = track_id;
  l.T_world_object = Eigen::Isometry3d::Identity();
  l.T_world_object.translation() = p_world;
  return l;
}

Eigen::Isometry3d camera(double x, double z, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, 0, z);
  return T;
}

TEST(ObjectAnchors, AnObjectMovesWithTheKeyFrameItWasFittedFrom) {
  ObjectMap objects;
  ObjectAnchors anchors;
  // Car 3 fitted from the keyframe of frame 10, car 4 from frame 20; car 5 from frame 30, which the final
  // trajectory does not have; car 6 was called moving (removed) after its fit.
  const Eigen::Isometry3d then10 = camera(0, 10, 0), then20 = camera(1, 20, 0.1);
  registry::Landmarks first = {car(3, {2, 0, 15}), car(6, {5, 0, 12})};
  applyLandmarkUpdates(objects, first);
  anchorLandmarkUpdates(anchors, first, {10, then10});
  registry::Landmarks second = {car(4, {-2, 0, 25}), car(5, {0, 0, 40})};
  applyLandmarkUpdates(objects, second);
  anchorLandmarkUpdates(anchors, second, {20, then20});
  registry::ObjectLandmark gone = car(6, Eigen::Vector3d::Zero());
  gone.removed = true;
  applyLandmarkUpdates(objects, {gone});
  anchorLandmarkUpdates(anchors, {gone}, {20, then20});
  EXPECT_EQ(anchors.count(6), 0u);

  // A loop correction moved frame 10 by 1.5 m and turned it, frame 20 not at all.
  const Eigen::Isometry3d final10 = camera(1.5, 10, 0.05);
  followFinalPoses(objects, anchors, {{10, 1.0, final10}, {20, 2.0, then20}});
  // Car 3 keeps its place in the keyframe's camera frame.
  const Eigen::Vector3d p_cam_then = then10.inverse() * Eigen::Vector3d(2, 0, 15);
  EXPECT_LT((objects.at(3).T_world_object.translation() - final10 * p_cam_then).norm(), 1e-12);
  EXPECT_LT((objects.at(3).T_world_object.linear() - final10.linear()).norm(), 1e-12);
  EXPECT_LT((objects.at(4).T_world_object.translation() - Eigen::Vector3d(-2, 0, 25)).norm(), 1e-12);
  EXPECT_LT((objects.at(5).T_world_object.translation() - Eigen::Vector3d(0, 0, 40)).norm(), 1e-12)
      << "no final pose for its keyframe: left where it was";
  EXPECT_EQ(objects.count(6), 0u);
}

// The reconstructor's finish() refits objects in the world of its last call: they keep their keyframe, now
// with the pose that call gave it, so a correction made before that call is not applied twice.
TEST(ObjectAnchors, FinalUpdatesHangOnTheirKeyframeAsTheLastCallSawIt) {
  ObjectMap objects;
  ObjectAnchors anchors;
  const Eigen::Isometry3d then10 = camera(0, 10, 0);
  registry::Landmarks first = {car(3, {2, 0, 15}), car(4, {-2, 0, 25}), car(5, {0, 0, 40})};
  applyLandmarkUpdates(objects, first);
  anchorLandmarkUpdates(anchors, first, {10, then10});
  // By the last call the keyframe of frame 10 had moved 1.5 m; finish() refits cars 3 and 5 there (car 5's
  // keyframe missing from that call) and removes car 4.
  const Eigen::Isometry3d last10 = camera(1.5, 10, 0);
  registry::ObjectLandmark gone = car(4, Eigen::Vector3d::Zero());
  gone.removed = true;
  const registry::Landmarks last = {car(3, {3.5, 0, 15}), car(5, {0, 0, 40}), gone};
  applyLandmarkUpdates(objects, last);
  const std::map<int64_t, Eigen::Isometry3d> given = {{20, camera(0, 20, 0)}};
  anchorFinalUpdates(anchors, {car(5, {0, 0, 40})}, given);
  EXPECT_EQ(anchors.count(5), 0u) << "its keyframe was not in the last call: no anchor";
  anchorFinalUpdates(anchors, last, {{10, last10}});
  EXPECT_EQ(anchors.count(4), 0u);
  ASSERT_EQ(anchors.count(3), 1u);
  // The final trajectory has frame 10 where the last call saw it: car 3 stays (not moved by 1.5 m again).
  followFinalPoses(objects, anchors, {{10, 1.0, last10}});
  EXPECT_LT((objects.at(3).T_world_object.translation() - Eigen::Vector3d(3.5, 0, 15)).norm(), 1e-12);
  EXPECT_LT((objects.at(5).T_world_object.translation() - Eigen::Vector3d(0, 0, 40)).norm(), 1e-12);
}

}  // namespace
}  // namespace beslam::pipeline::detail
