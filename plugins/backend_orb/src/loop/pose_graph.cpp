#include "loop/pose_graph.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>
#include <stdexcept>

namespace beslam::orb::loop {
namespace {

// Node parameters: [angle-axis (3), t (3), log s (1)] of S_cw.
void toParams(const Sim3& S, double* p) {
  ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(S.R.data()), p);
  for (int k = 0; k < 3; ++k) p[3 + k] = S.t[k];
  p[6] = std::log(S.s);
}

Sim3 fromParams(const double* p) {
  Sim3 S;
  ceres::AngleAxisToRotationMatrix(p, ceres::ColumnMajorAdapter3x3(S.R.data()));
  S.t = Eigen::Vector3d(p[3], p[4], p[5]);
  S.s = std::exp(p[6]);
  return S;
}

struct EdgeResidual {
  EdgeResidual(const Sim3& S_ij, double weight) : S_ji_measured(S_ij.inverse()), sqrt_weight(std::sqrt(weight)) {}

  template <class T>
  bool operator()(const T* pi, const T* pj, T* residual) const {
    using M3 = Eigen::Matrix<T, 3, 3>;
    using V3 = Eigen::Matrix<T, 3, 1>;
    M3 Ri, Rj;
    ceres::AngleAxisToRotationMatrix(pi, ceres::ColumnMajorAdapter3x3(Ri.data()));
    ceres::AngleAxisToRotationMatrix(pj, ceres::ColumnMajorAdapter3x3(Rj.data()));
    const V3 ti(pi[3], pi[4], pi[5]), tj(pj[3], pj[4], pj[5]);
    const T si = exp(pi[6]), sj = exp(pj[6]);
    // S_i * S_j^-1 = (si / sj, Ri Rj^T, ti - (si / sj) Ri Rj^T tj)
    const M3 R_ij = Ri * Rj.transpose();
    const T s_ij = si / sj;
    const V3 t_ij = ti - s_ij * (R_ij * tj);
    // E = measured^-1 * (S_i S_j^-1)
    const M3 Rm = S_ji_measured.R.cast<T>();
    const V3 tm = S_ji_measured.t.cast<T>();
    const T sm = T(S_ji_measured.s);
    const M3 R_e = Rm * R_ij;
    const V3 t_e = sm * (Rm * t_ij) + tm;
    const T s_e = sm * s_ij;
    ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(R_e.data()), residual);
    for (int k = 0; k < 3; ++k) residual[3 + k] = t_e[k];
    residual[6] = log(s_e);
    for (int k = 0; k < 7; ++k) residual[k] *= T(sqrt_weight);
    return true;
  }

  Sim3 S_ji_measured;
  double sqrt_weight;
};

}  // namespace

PoseGraphResult optimizePoseGraph(const PoseGraph& graph, int max_iterations, bool fix_scale) {
  const size_t n = graph.S_cw.size();
  if (graph.fixed.size() != n) throw std::invalid_argument("pose graph: one fixed flag per node needed");
  std::vector<double> params(7 * n);
  for (size_t i = 0; i < n; ++i) toParams(graph.S_cw[i], &params[7 * i]);

  ceres::Problem problem;
  for (const PoseGraph::Edge& e : graph.edges) {
    if (e.i < 0 || e.j < 0 || static_cast<size_t>(e.i) >= n || static_cast<size_t>(e.j) >= n || e.i == e.j)
      throw std::invalid_argument("pose graph: edge with a bad node index");
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<EdgeResidual, 7, 7, 7>(new EdgeResidual(e.S_ij, e.weight)),
                             nullptr, &params[7 * e.i], &params[7 * e.j]);
  }
  for (size_t i = 0; i < n; ++i) {
    double* block = &params[7 * i];
    if (!problem.HasParameterBlock(block)) continue;
    if (graph.fixed[i])
      problem.SetParameterBlockConstant(block);
    else if (fix_scale)
      problem.SetManifold(block, new ceres::SubsetManifold(7, {6}));
  }

  PoseGraphResult result;
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  if (problem.NumResidualBlocks() > 0) {
    ceres::Solve(options, &problem, &summary);
    result.initial_cost = summary.initial_cost;
    result.final_cost = summary.final_cost;
    result.iterations = static_cast<int>(summary.iterations.size());
  }
  result.S_cw.reserve(n);
  for (size_t i = 0; i < n; ++i) result.S_cw.push_back(fromParams(&params[7 * i]));
  return result;
}

}  // namespace beslam::orb::loop
