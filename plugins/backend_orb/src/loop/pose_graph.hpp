// Pose-graph optimisation over similarity transforms, the core of ORB-SLAM2's essential-graph step
// after a loop: nodes are keyframes' S_cw (world -> camera, with scale for a monocular map), edges are
// relative measurements S_ij = S_i S_j^-1 (spanning tree, strong covisibility and loop links). The
// residual of an edge is the 7-vector [rotation (angle-axis), translation, log scale] of
// S_ij^-1 S_i S_j^-1, weighted; Levenberg-Marquardt with Ceres (sparse normal Cholesky).
// fix_scale turns every node into SE3 (scale held at its start), as a metric map needs.
#pragma once

#include <vector>

#include "loop/sim3.hpp"

namespace beslam::orb::loop {

struct PoseGraph {
  struct Edge {
    int i = 0, j = 0;
    Sim3 S_ij;  // measured S_i * S_j^-1
    double weight = 1.0;
  };
  std::vector<Sim3> S_cw;   // start values of the nodes
  std::vector<bool> fixed;  // per node: held where it is (the loop keyframe, the map's origin)
  std::vector<Edge> edges;
};

struct PoseGraphResult {
  std::vector<Sim3> S_cw;
  double initial_cost = 0, final_cost = 0;
  int iterations = 0;
};

PoseGraphResult optimizePoseGraph(const PoseGraph& graph, int max_iterations, bool fix_scale);

}  // namespace beslam::orb::loop
