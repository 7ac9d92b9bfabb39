// The parked-car layout check of loop closing and relocalisation (objects/object_layout.hpp): two layouts
// agree, disagree or leave the decision open; a car's place is its landmark's centre where the map holds
// one, which is what lets a street driven the other way round agree with itself.
#include "objects/object_layout.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "map_builder.hpp"
#include "objects/object_store.hpp"

using namespace beslam::orb;

namespace {

std::vector<Eigen::Vector3d> shifted(std::vector<Eigen::Vector3d> cars, const Eigen::Vector3d& by) {
  for (Eigen::Vector3d& p : cars) p += by;
  return cars;
}

}  // namespace

TEST(ObjectLayout, AgreesDisagreesOrWaitsForEnoughCars) {
  // Four parked cars along a kerb, 7 m apart, seen from the camera (x right, z ahead).
  const std::vector<Eigen::Vector3d> kerb = {{3, 1, 8}, {3, 1, 15}, {-3, 1, 22}, {3, 1, 29}};
  const objects::LayoutOptions o;  // 2.5 m, more than half must disagree, 2 cars on each side
  objects::LayoutCheck c = objects::compareLayouts(kerb, shifted(kerb, {0.4, 0, -0.8}), o);
  EXPECT_TRUE(c.decided);
  EXPECT_EQ(c.compared, 4);
  EXPECT_EQ(c.disagree, 0);
  EXPECT_FALSE(c.rejected);
  // The wrong place: the same kind of street a block on (the layout 3.5 m along it: every car between two).
  c = objects::compareLayouts(kerb, shifted(kerb, {0, 0, 3.5}), o);
  EXPECT_EQ(c.disagree, 4);
  EXPECT_TRUE(c.rejected);
  // Half of them moved away since (2 of 4 disagree): not more than half, kept.
  std::vector<Eigen::Vector3d> half = kerb;
  half[1].z() += 5, half[3].x() -= 6;
  c = objects::compareLayouts(kerb, half, o);
  EXPECT_EQ(c.disagree, 2);
  EXPECT_FALSE(c.rejected);
  half[0].x() += 4;
  EXPECT_TRUE(objects::compareLayouts(kerb, half, o).rejected);
  // One car on a side: no decision either way.
  c = objects::compareLayouts(kerb, {kerb[0] + Eigen::Vector3d(0, 0, 20)}, o);
  EXPECT_FALSE(c.decided);
  EXPECT_FALSE(c.rejected);
  EXPECT_FALSE(objects::compareLayouts({}, kerb, o).decided);
}

TEST(ObjectLayout, LandmarkCentresAgreeWhereSurfaceCentroidsDoNot) {
  // Two cars parked along the road (4.4 m long, along z), passed on the way out and again on the way back.
  // Out, the camera sees their rears; back, their fronts (new tracks: 17, 18 instead of 7, 8). The
  // centroid of the points a keyframe has on a car lies on the side it saw: 4.4 m apart between the two
  // passes, beyond the check's 2.5 m. The reconstructed cars' centres are the same both times.
  const Camera cam{1241, 376, 718.856, 718.856, 607.193, 185.216};
  const ScalePyramid pyr(8, 1.2);
  Map map;
  const std::vector<Eigen::Vector3d> centres = {{3, 0.8, 10}, {-3, 0.8, 25}};
  auto keyframeSeeing = [&](int64_t frame, int first_id, double face) {
    std::vector<cv::KeyPoint> keypoints(12, cv::KeyPoint(600.f, 180.f, 31.f));
    Frame f(frame, 0.1 * frame, test::blankFeatures(cam, keypoints));
    KeyFrame* kf = map.createKeyFrame(f, cam, pyr);
    for (size_t i = 0; i < keypoints.size(); ++i) {
      const int car = static_cast<int>(i) / 6;
      const Eigen::Vector3d on_face =
          centres[car] + Eigen::Vector3d(0.7 * ((i % 3) - 1.0), 0.5 * ((i % 2) - 0.5), face * 2.2);
      MapPoint* mp = map.createMapPoint(on_face, kf);
      mp->trusted = true;
      mp->object_id = first_id + car;
      kf->addPoint(mp, i);
      mp->addObservation(kf, i);
    }
    return kf;
  };
  const KeyFrame* out = keyframeSeeing(0, 7, -1.0);
  const KeyFrame* back = keyframeSeeing(1, 17, +1.0);
  const objects::LayoutOptions o;
  EXPECT_TRUE(objects::compareLayouts(objects::parkedCarCentres(*out, map.objects()),
                                      objects::parkedCarCentres(*back, map.objects()), o)
                  .rejected)
      << "the surface centroids of the two passes are a car's length apart";
  for (int64_t id : {7, 8, 17, 18}) {
    ObjectLandmark l;
    l.id = id;
    l.T_world_object.translation() = centres[(id % 10) - 7] + Eigen::Vector3d(0.1, 0, id > 10 ? -0.2 : 0.2);
    l.dimensions = Eigen::Vector3d(4.4, 1.8, 1.5);
    map.objects().add(l, 1);
  }
  const auto cars_out = objects::parkedCarCentres(*out, map.objects());
  ASSERT_EQ(cars_out.size(), 2u);
  EXPECT_LT((cars_out[0] - centres[0]).norm(), 0.3);
  const objects::LayoutCheck c = objects::compareLayouts(cars_out, objects::parkedCarCentres(*back, map.objects()), o);
  EXPECT_TRUE(c.decided);
  EXPECT_EQ(c.disagree, 0);
  // A car with fewer than 3 points in the keyframe is not counted.
  EXPECT_TRUE(objects::parkedCarCentres(*out, map.objects(), 7).empty());
}

TEST(ObjectLayout, OnlyCarsTheFrameCouldShowAreExpected) {
  // KITTI's camera; the frame's farthest car box at 30 m.
  const Camera cam{1241, 376, 718.856, 718.856, 607.193, 185.216};
  const std::vector<Eigen::Vector3d> cars = {
      {3, 1, 12},   // in view
      {-4, 1, 25},  // in view
      {3, 1, -8},   // behind the camera (a candidate keyframe from before the blackout)
      {3, 1, 0.5},  // beside it
      {30, 1, 10},  // outside the image to the right
      {2, 1, 45},   // in the image, beyond the detector's reach here
  };
  const auto in_view = objects::carsInView(cars, cam, 30.0);
  ASSERT_EQ(in_view.size(), 2u);
  EXPECT_EQ(in_view[0], cars[0]);
  EXPECT_EQ(in_view[1], cars[1]);
  EXPECT_EQ(objects::carsInView(cars, cam, 50.0).size(), 3u);
}
