// The layout of parked cars as a check of place (BE-SLAM's BEV object check). Loop closing compares the
// cars the loop keyframe sees, moved by the loop transform, with the ones the new keyframe sees;
// relocalisation compares the cars the candidate keyframe sees, placed by the recovered pose, with the
// frame's own car boxes. A place whose parked cars mostly stand where the view has no car is the wrong place.
//
// Where a car stands: its reconstructed landmark's centre when the map holds one (the centre of the whole
// car, the same from every side), else the centroid of its trusted map points (the side the camera saw:
// up to half a car's width or length from its centre, and on the far side when the car is seen the other
// way round, as on the way back along a street).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "beslam_orb/options.hpp"

namespace beslam::orb {
class KeyFrame;
}

namespace beslam::orb::objects {

class ObjectStore;

// World positions of the parked cars keyframe kf sees: each object with at least min_points trusted map
// points in kf, at its landmark's centre in `store` when there is one, else at those points' centroid.
// Ordered by object id.
std::vector<Eigen::Vector3d> parkedCarCentres(const KeyFrame& kf, const ObjectStore& store, int min_points = 3);

// Of the cars p_cam (camera frame, metres), those a frame could show: at least 1 m in front of the camera,
// projecting inside the image, and no farther than `reach` (how far the frame's detector saw cars).
std::vector<Eigen::Vector3d> carsInView(const std::vector<Eigen::Vector3d>& p_cam, const Camera& camera, double reach);

struct LayoutOptions {
  double radius = 2.5;            // a car "agrees" when the other side has one within this distance
  double max_disagreement = 0.5;  // the layouts disagree when more than this share of `expected` cars do
  int min_cars = 2;               // no decision unless both sides have at least this many cars
};

struct LayoutCheck {
  bool decided = false;   // both sides had min_cars
  int compared = 0;       // cars of `expected` (when decided)
  int disagree = 0;       // of them, with no car of `seen` within the radius
  bool rejected = false;  // decided and disagree > max_disagreement * compared
};

// expected and seen in one frame (a camera's): the cars one side predicts there and the ones the other
// side sees.
LayoutCheck compareLayouts(const std::vector<Eigen::Vector3d>& expected, const std::vector<Eigen::Vector3d>& seen,
                           const LayoutOptions& options);

}  // namespace beslam::orb::objects
