// A static map scored against a synthetic sequence's truth (label_02 boxes, objects_motion.txt, poses):
// occupied voxels on the trails of moving cars (inside a car's box at a frame where it moves, and
// inside no box of an object while it stands: a car that parked there or a standing pedestrian is
// rightly mapped) and inside the boxes of cars that never move (static scene kept). A voxel counts as inside a box when
// it lies wholly inside (its centre inside the box shrunk by half a voxel); trail voxels must also lie 0.3 m or more
// above the box's bottom (below is road and kerb: label boxes sit a few cm into the road). The map is brought into the
// truth's world frame by the run's trajectory alignment (summary.json evaluation.alignment).
#pragma once

#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace beslam::static_map {

struct MapScore {
  int64_t occupied = 0;            // occupied voxels of the map's resolution
  int64_t in_moving_paths = 0;     // ... on a moving car's trail (see above)
  int64_t in_parked_cars = 0;      // ... wholly inside the box of a car that never moves
  int64_t parked_cars = 0;         // cars that never move, seen within `near` metres
  int64_t parked_cars_mapped = 0;  // ... with at least one occupied voxel inside
};

struct Similarity {  // p_truth = scale * R * p_map + t
  double scale = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};

// sequence_dir: KITTI layout root/sequences/NN with label_02/NN.txt and objects_motion.txt; the poses
// are root/poses/NN.txt. Throws beslam::Error naming a missing or malformed file.
MapScore scoreStaticMap(const octomap::OcTree& tree, const std::string& sequence_dir, const std::string& sequence,
                        const Similarity& map_to_truth, double near = 20.0);

// `beslam eval-static-map`: see its --help.
int runEvalCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace beslam::static_map
