#include "optimize/schur_lm.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numeric>
#include <opencv2/core/utility.hpp>
#include <stdexcept>

#include "optimize/lm_damping.hpp"
#include "optimize/se3.hpp"

namespace beslam::orb::optimize {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix63 = Eigen::Matrix<double, 6, 3>;

// Fixed, whatever the thread count: the sums of each range are added in range order.
constexpr int kRanges = 2;
constexpr int kMaxRows = 3;
using lm::clampDiagonal;

void runRanges(const std::function<void(int)>& work) {
  cv::parallel_for_(
      cv::Range(0, kRanges),
      [&](const cv::Range& r) {
        for (int c = r.start; c < r.end; ++c) work(c);
      },
      kRanges);
}

// What one range of 3-vectors adds to the reduced system; the ranges' sums are added in range order.
struct RangeSums {
  std::vector<Matrix6d> U;
  std::vector<Vector6d> gp;
  Eigen::MatrixXd S;               // upper blocks of sum W V^-1 W^T (dense)
  std::vector<Matrix6d> S_blocks;  // the same by block_pos (sparse)
  Eigen::VectorXd t;               // sum W V^-1 gx
  double cost = 0, predicted = 0;
};

}  // namespace

int SchurLevenbergMarquardt::addPose(double* pose, bool fixed) {
  poses_.push_back(pose);
  pose_fixed_.push_back(fixed);
  return static_cast<int>(poses_.size()) - 1;
}

int SchurLevenbergMarquardt::addVector(double* x) {
  vectors_.push_back(x);
  return static_cast<int>(vectors_.size()) - 1;
}

void SchurLevenbergMarquardt::addResidual(const ceres::CostFunction* cost, const ceres::LossFunction* loss, int pose,
                                          int vector) {
  const auto& sizes = cost->parameter_block_sizes();
  if (cost->num_residuals() < 1 || cost->num_residuals() > kMaxRows || sizes.size() != 2 || sizes[0] != 7 ||
      sizes[1] != 3)
    throw std::invalid_argument("SchurLevenbergMarquardt: a residual block must be 1-3 rows on (pose 7, vector 3)");
  residuals_.push_back({cost, loss, pose, vector});
}

// One solve(). Its layout (which unknown each moving pose is, which residuals and poses meet at each 3-vector,
// the blocks of a sparse reduced system, the 3-vector ranges) is found once; then each LM step builds the
// damped reduced system over the poses, solves it, back-substitutes the 3-vectors' steps and tries the
// candidate. Names follow the Schur complement: U, gp the poses' blocks and gradient; V, gx the 3-vectors';
// W the pose x 3-vector blocks; S dp = b the reduced system; dx the 3-vectors' step.
class SchurLevenbergMarquardt::Solver {
 public:
  explicit Solver(const SchurLevenbergMarquardt& problem);
  Summary run(int max_iterations);

 private:
  // The layout.
  void assignSlots();
  void groupByVector();
  void findSparseBlocks();
  void splitRanges();
  void copyState();
  void allocate();

  // Costs and the linearisation at the current state.
  double residualCost(const Residual& r, const double* pose, const double* vec) const;
  double costAt(const std::vector<double>& pose, const std::vector<double>& vec);
  void lineariseRange(int c);
  double linearise();

  // One damped step.
  bool solveDampedSystem();
  void reduceRange(int c);
  Matrix6d dampedU(int k) const;
  bool solveDense();
  bool solveSparse();
  double predictedDecrease();
  double backSubstituteRange(int c);
  void makeCandidate();
  bool candidateConverged(double cost, double new_cost) const;
  void writeBack() const;

  const std::vector<double*>& poses_;
  const std::vector<double*>& vectors_;
  const std::vector<bool>& pose_fixed_;
  const std::vector<Residual>& residuals_;
  const int n_poses, n_vectors;

  // Moving poses are the unknowns of the reduced system, in the order they were added: slot[pose] (-1: fixed).
  std::vector<int> slot;
  int n = 0, dim = 0;
  // Residuals grouped by 3-vector (then pose, then the order given): residuals_[order[i]] for i in
  // [res_begin[v], res_begin[v + 1]); per vector its moving poses (pairs) pair_slot[p] for p in
  // [pair_begin[v], pair_begin[v + 1]); res_pair[i] the pair of residual i (-1: fixed pose).
  std::vector<int> order, res_begin, pair_begin, pair_slot, res_pair;
  // Sparse (past kMaxDensePoses): the 6 x 6 blocks of the reduced system, and each pair's blocks.
  bool sparse = false;
  std::vector<std::pair<int, int>> block_pos;  // (row slot, column slot), column >= row, sorted
  std::vector<int> pair_block_begin, pair_block;
  // Vector ranges of about equal residual counts: [range_begin[c], range_begin[c + 1]).
  std::array<int, kRanges + 1> range_begin{};

  // State: current and candidate copies (cost functions read them through params pointers).
  std::vector<double> pose_now, pose_try, vec_now, vec_try;

  // The linearisation at the current state.
  std::vector<Eigen::Matrix3d> V, V_inv;
  std::vector<Eigen::Vector3d> gx, dx;
  std::vector<Matrix63> W;
  std::array<RangeSums, kRanges> sums;
  std::vector<Matrix6d> U_total;
  std::vector<Vector6d> gp_total;

  // The step.
  lm::Damping damping;
  Eigen::MatrixXd S;
  Eigen::VectorXd b, dp;
  // Sparse: the upper triangle in a fixed pattern (one triplet per block entry, in block_pos order), its
  // fill-reducing ordering and symbolic factorisation computed once.
  Eigen::SparseMatrix<double> S_sparse;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::AMDOrdering<int>> sparse_llt;
  bool analysed = false;
  std::vector<Eigen::Triplet<double>> triplets;
};

SchurLevenbergMarquardt::Solver::Solver(const SchurLevenbergMarquardt& problem)
    : poses_(problem.poses_),
      vectors_(problem.vectors_),
      pose_fixed_(problem.pose_fixed_),
      residuals_(problem.residuals_),
      n_poses(static_cast<int>(poses_.size())),
      n_vectors(static_cast<int>(vectors_.size())) {
  assignSlots();
  groupByVector();
  sparse = n > kMaxDensePoses;
  if (sparse) findSparseBlocks();
  splitRanges();
  copyState();
  allocate();
}

void SchurLevenbergMarquardt::Solver::assignSlots() {
  slot.assign(n_poses, -1);
  for (int k = 0; k < n_poses; ++k)
    if (!pose_fixed_[k]) slot[k] = n++;
  dim = 6 * n;
}

void SchurLevenbergMarquardt::Solver::groupByVector() {
  order.resize(residuals_.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int i, int j) {
    return residuals_[i].vector != residuals_[j].vector ? residuals_[i].vector < residuals_[j].vector
                                                        : residuals_[i].pose < residuals_[j].pose;
  });
  res_begin.assign(n_vectors + 1, 0);
  pair_begin.assign(n_vectors + 1, 0);
  res_pair.assign(order.size(), -1);
  for (const Residual& r : residuals_) ++res_begin[r.vector + 1];
  std::partial_sum(res_begin.begin(), res_begin.end(), res_begin.begin());
  for (int v = 0; v < n_vectors; ++v) {
    pair_begin[v] = static_cast<int>(pair_slot.size());
    for (int i = res_begin[v]; i < res_begin[v + 1]; ++i) {
      const int s = slot[residuals_[order[i]].pose];
      if (s < 0) continue;
      if (pair_slot.size() == static_cast<size_t>(pair_begin[v]) || pair_slot.back() != s) pair_slot.push_back(s);
      res_pair[i] = static_cast<int>(pair_slot.size()) - 1;  // sorted by pose: equal slots are adjacent
    }
  }
  pair_begin[n_vectors] = static_cast<int>(pair_slot.size());
}

// Past kMaxDensePoses the reduced system is block-sparse: a 6 x 6 block for each pair of poses that share
// a 3-vector (a global BA's covisibility), found once; each vector's pair (a, b >= a) names its block.
void SchurLevenbergMarquardt::Solver::findSparseBlocks() {
  for (int v = 0; v < n_vectors; ++v)
    for (int a = pair_begin[v]; a < pair_begin[v + 1]; ++a)
      for (int bb = a; bb < pair_begin[v + 1]; ++bb) block_pos.emplace_back(pair_slot[a], pair_slot[bb]);
  for (int k = 0; k < n; ++k) block_pos.emplace_back(k, k);  // every diagonal block, shared or not
  std::sort(block_pos.begin(), block_pos.end());
  block_pos.erase(std::unique(block_pos.begin(), block_pos.end()), block_pos.end());
  pair_block_begin.assign(pair_slot.size() + 1, 0);
  for (int v = 0; v < n_vectors; ++v)
    for (int a = pair_begin[v]; a < pair_begin[v + 1]; ++a) {
      pair_block_begin[a] = static_cast<int>(pair_block.size());
      for (int bb = a; bb < pair_begin[v + 1]; ++bb)
        pair_block.push_back(static_cast<int>(
            std::lower_bound(block_pos.begin(), block_pos.end(), std::make_pair(pair_slot[a], pair_slot[bb])) -
            block_pos.begin()));
    }
  pair_block_begin[pair_slot.size()] = static_cast<int>(pair_block.size());
}

void SchurLevenbergMarquardt::Solver::splitRanges() {
  range_begin[kRanges] = n_vectors;
  for (int c = 1, v = 0; c < kRanges; ++c) {
    const long target = static_cast<long>(residuals_.size()) * c / kRanges;
    while (v < n_vectors && res_begin[v] < target) ++v;
    range_begin[c] = v;
  }
}

void SchurLevenbergMarquardt::Solver::copyState() {
  pose_now.resize(7 * n_poses);
  pose_try.resize(7 * n_poses);
  vec_now.resize(3 * n_vectors);
  vec_try.resize(3 * n_vectors);
  for (int k = 0; k < n_poses; ++k) std::copy(poses_[k], poses_[k] + 7, &pose_now[7 * k]);
  for (int v = 0; v < n_vectors; ++v) std::copy(vectors_[v], vectors_[v] + 3, &vec_now[3 * v]);
}

void SchurLevenbergMarquardt::Solver::allocate() {
  V.resize(n_vectors);
  V_inv.resize(n_vectors);
  gx.resize(n_vectors);
  dx.resize(n_vectors);
  W.resize(pair_slot.size());
  U_total.resize(n);
  gp_total.resize(n);
  for (RangeSums& s : sums) {
    s.U.assign(n, Matrix6d::Zero());
    s.gp.assign(n, Vector6d::Zero());
  }
  S.resize(sparse ? 0 : dim, sparse ? 0 : dim);
  b.resize(dim);
  dp.resize(dim);
  S_sparse.resize(dim, dim);
}

double SchurLevenbergMarquardt::Solver::residualCost(const Residual& r, const double* pose, const double* vec) const {
  double res[kMaxRows];
  const double* params[] = {pose, vec};
  r.cost->Evaluate(params, res, nullptr);
  double sq = 0;
  for (int i = 0; i < r.cost->num_residuals(); ++i) sq += res[i] * res[i];
  if (!r.loss) return 0.5 * sq;
  double rho[3];
  r.loss->Evaluate(sq, rho);
  return 0.5 * rho[0];
}

double SchurLevenbergMarquardt::Solver::costAt(const std::vector<double>& pose, const std::vector<double>& vec) {
  runRanges([&](int c) {
    double cost = 0;
    for (int i = res_begin[range_begin[c]]; i < res_begin[range_begin[c + 1]]; ++i) {
      const Residual& r = residuals_[order[i]];
      cost += residualCost(r, &pose[7 * r.pose], &vec[3 * r.vector]);
    }
    sums[c].cost = cost;
  });
  double total = 0;
  for (const RangeSums& s : sums) total += s.cost;
  return total;
}

// Range c's residuals at the current state: its vectors' V, gx and W, and its sums U, gp and cost.
void SchurLevenbergMarquardt::Solver::lineariseRange(int c) {
  RangeSums& s = sums[c];
  std::fill(s.U.begin(), s.U.end(), Matrix6d::Zero());
  std::fill(s.gp.begin(), s.gp.end(), Vector6d::Zero());
  double cost = 0;
  double res[kMaxRows], J_pose[kMaxRows * 7], J_vec[kMaxRows * 3];
  double* jacobians[] = {J_pose, J_vec};
  for (int v = range_begin[c]; v < range_begin[c + 1]; ++v) {
    V[v].setZero();
    gx[v].setZero();
    for (int p = pair_begin[v]; p < pair_begin[v + 1]; ++p) W[p].setZero();
    for (int i = res_begin[v]; i < res_begin[v + 1]; ++i) {
      const Residual& r = residuals_[order[i]];
      const double* params[] = {&pose_now[7 * r.pose], &vec_now[3 * v]};
      r.cost->Evaluate(params, res, jacobians);
      const int rows = r.cost->num_residuals();
      double sq = 0;
      for (int j = 0; j < rows; ++j) sq += res[j] * res[j];
      double rho[3] = {sq, 1, 0};
      if (r.loss) r.loss->Evaluate(sq, rho);
      cost += 0.5 * rho[0];
      const double w = rho[1];  // iteratively reweighted least squares
      const int k = slot[r.pose];
      for (int j = 0; j < rows; ++j) {
        const Eigen::Map<const Eigen::Vector3d> jx(&J_vec[3 * j]);
        V[v].noalias() += w * jx * jx.transpose();
        gx[v] += (w * res[j]) * jx;
        if (k < 0) continue;
        const Eigen::Map<const Vector6d> jp(&J_pose[7 * j]);  // the tangent part: first six columns
        W[res_pair[i]].noalias() += w * jp * jx.transpose();
        s.U[k].noalias() += w * jp * jp.transpose();
        s.gp[k] += (w * res[j]) * jp;
      }
    }
  }
  s.cost = cost;
}

// Linearises at the current state; returns its cost.
double SchurLevenbergMarquardt::Solver::linearise() {
  runRanges([&](int c) { lineariseRange(c); });
  double cost = 0;
  for (const RangeSums& s : sums) cost += s.cost;
  for (int k = 0; k < n; ++k) {  // the moving poses' blocks, summed over the ranges in order
    U_total[k].setZero();
    gp_total[k].setZero();
    for (const RangeSums& s : sums) {
      U_total[k] += s.U[k];
      gp_total[k] += s.gp[k];
    }
  }
  return cost;
}

// The damped reduced system S dp = b, solved for dp; false when it cannot be.
bool SchurLevenbergMarquardt::Solver::solveDampedSystem() {
  runRanges([&](int c) { reduceRange(c); });
  b.setZero();
  for (int k = 0; k < n; ++k) b.segment<6>(6 * k) = -gp_total[k];
  for (const RangeSums& s : sums) b += s.t;
  if (dim == 0) return true;
  return sparse ? solveSparse() : solveDense();
}

// Range c's part of the reduced system: its vectors' damped V^-1, and sum W V^-1 W^T, sum W V^-1 gx.
void SchurLevenbergMarquardt::Solver::reduceRange(int c) {
  const double mu = damping.mu;
  RangeSums& s = sums[c];
  if (sparse)
    s.S_blocks.assign(block_pos.size(), Matrix6d::Zero());
  else
    s.S.setZero(dim, dim);
  s.t.setZero(dim);
  for (int v = range_begin[c]; v < range_begin[c + 1]; ++v) {
    if (res_begin[v] == res_begin[v + 1]) {  // no residual: does not move
      V_inv[v].setZero();
      continue;
    }
    Eigen::Matrix3d Vd = V[v];
    for (int d = 0; d < 3; ++d) Vd(d, d) += mu * clampDiagonal(V[v](d, d));
    bool invertible = false;
    double det = 0;
    Vd.computeInverseAndDetWithCheck(V_inv[v], det, invertible, 1e-300);
    if (!invertible || !(det > 0)) V_inv[v].setZero();  // not constrained: stays where it is
    for (int a = pair_begin[v]; a < pair_begin[v + 1]; ++a) {
      const Matrix63 WV = W[a] * V_inv[v];
      s.t.segment<6>(6 * pair_slot[a]) += WV * gx[v];
      for (int bb = a; bb < pair_begin[v + 1]; ++bb) {  // slots increase along a vector's pairs
        if (sparse)
          s.S_blocks[pair_block[pair_block_begin[a] + (bb - a)]].noalias() += WV * W[bb].transpose();
        else
          s.S.block<6, 6>(6 * pair_slot[a], 6 * pair_slot[bb]).noalias() += WV * W[bb].transpose();
      }
    }
  }
}

Matrix6d SchurLevenbergMarquardt::Solver::dampedU(int k) const {
  const double mu = damping.mu;
  Matrix6d U = U_total[k];
  for (int d = 0; d < 6; ++d) U(d, d) += mu * clampDiagonal(U(d, d));
  return U;
}

bool SchurLevenbergMarquardt::Solver::solveDense() {
  S.setZero();
  for (int k = 0; k < n; ++k) S.block<6, 6>(6 * k, 6 * k) = dampedU(k);
  for (const RangeSums& s : sums) S -= s.S;
  const Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> llt(S);
  if (llt.info() != Eigen::Success) return false;
  dp = llt.solve(b);
  return dp.allFinite();
}

bool SchurLevenbergMarquardt::Solver::solveSparse() {
  triplets.clear();
  for (size_t blk = 0; blk < block_pos.size(); ++blk) {
    const auto [row, col] = block_pos[blk];
    Matrix6d B = row == col ? dampedU(row) : Matrix6d::Zero();
    for (const RangeSums& s : sums) B -= s.S_blocks[blk];
    for (int i = 0; i < 6; ++i)
      for (int j = row == col ? i : 0; j < 6; ++j) triplets.emplace_back(6 * row + i, 6 * col + j, B(i, j));
  }
  S_sparse.setFromTriplets(triplets.begin(), triplets.end());
  if (!analysed) {
    sparse_llt.analyzePattern(S_sparse);
    analysed = true;
  }
  sparse_llt.factorize(S_sparse);
  if (sparse_llt.info() != Eigen::Success) return false;
  dp = sparse_llt.solve(b);
  return dp.allFinite();
}

// Back-substitutes the 3-vectors' step dx and returns the decrease the linear model predicts: with the
// gradient g = [gp; gx], 0.5 (-g.d + mu d.D.d) (Ceres' LM).
double SchurLevenbergMarquardt::Solver::predictedDecrease() {
  const double mu = damping.mu;
  double predicted = 0;
  for (int k = 0; k < n; ++k) {
    const Vector6d d = dp.segment<6>(6 * k);
    for (int i = 0; i < 6; ++i)
      predicted += 0.5 * (-gp_total[k](i) * d(i) + mu * clampDiagonal(U_total[k](i, i)) * d(i) * d(i));
  }
  runRanges([&](int c) { sums[c].predicted = backSubstituteRange(c); });
  for (const RangeSums& s : sums) predicted += s.predicted;
  return predicted;
}

// Range c's vectors' dx; returns their part of the predicted decrease.
double SchurLevenbergMarquardt::Solver::backSubstituteRange(int c) {
  const double mu = damping.mu;
  double part = 0;
  for (int v = range_begin[c]; v < range_begin[c + 1]; ++v) {
    Eigen::Vector3d rhs = -gx[v];
    for (int a = pair_begin[v]; a < pair_begin[v + 1]; ++a)
      rhs.noalias() -= W[a].transpose() * dp.segment<6>(6 * pair_slot[a]);
    dx[v] = V_inv[v] * rhs;
    for (int i = 0; i < 3; ++i)
      part += 0.5 * (-gx[v](i) * dx[v](i) + mu * clampDiagonal(V[v](i, i)) * dx[v](i) * dx[v](i));
  }
  return part;
}

// The candidate state: the current one moved by dp and dx.
void SchurLevenbergMarquardt::Solver::makeCandidate() {
  const SE3LeftManifold manifold;
  for (int k = 0; k < n_poses; ++k) {
    if (slot[k] < 0) {
      std::copy(&pose_now[7 * k], &pose_now[7 * k] + 7, &pose_try[7 * k]);
      continue;
    }
    manifold.Plus(&pose_now[7 * k], dp.data() + 6 * slot[k], &pose_try[7 * k]);
  }
  for (int v = 0; v < n_vectors; ++v) {
    const bool used = res_begin[v] < res_begin[v + 1];
    for (int i = 0; i < 3; ++i) vec_try[3 * v + i] = vec_now[3 * v + i] + (used ? dx[v](i) : 0.0);
  }
}

// Ceres' convergence tests, on the candidate before it is accepted: a step this small, or a cost change
// this small, ends the solve where it is (the candidate is dropped).
bool SchurLevenbergMarquardt::Solver::candidateConverged(double cost, double new_cost) const {
  double step_sq = dp.squaredNorm(), x_sq = 0;
  for (int v = 0; v < n_vectors; ++v)
    if (res_begin[v] < res_begin[v + 1]) step_sq += dx[v].squaredNorm();
  for (double x : pose_now) x_sq += x * x;
  for (double x : vec_now) x_sq += x * x;
  return lm::converged(std::sqrt(step_sq), std::sqrt(x_sq), cost, new_cost);
}

// The moving poses and every 3-vector back into the caller's blocks.
void SchurLevenbergMarquardt::Solver::writeBack() const {
  for (int k = 0; k < n_poses; ++k)
    if (slot[k] >= 0) std::copy(&pose_now[7 * k], &pose_now[7 * k] + 7, poses_[k]);
  for (int v = 0; v < n_vectors; ++v) std::copy(&vec_now[3 * v], &vec_now[3 * v] + 3, vectors_[v]);
}

SchurLevenbergMarquardt::Summary SchurLevenbergMarquardt::Solver::run(int max_iterations) {
  Summary summary;
  double cost = linearise();
  summary.initial_cost = cost;
  summary.iterations = 1;
  for (int step = 0; step < max_iterations; ++step) {  // steps tried, successful or not (Ceres' iterations)
    const bool solved = solveDampedSystem();
    const double predicted = solved ? predictedDecrease() : 0;
    const bool tried = solved && predicted > 0;
    double new_cost = cost;
    if (tried) {
      makeCandidate();
      new_cost = costAt(pose_try, vec_try);
      if (candidateConverged(cost, new_cost)) break;
    }
    const double rho = tried ? (cost - new_cost) / predicted : -1;
    if (std::isfinite(new_cost) && rho > lm::kMinRelativeDecrease) {
      pose_now.swap(pose_try);
      vec_now.swap(vec_try);
      damping.accepted(rho);
      if (step + 1 == max_iterations) {
        cost = new_cost;
        break;
      }
      cost = linearise();
      ++summary.iterations;
    } else if (!damping.refused()) {
      break;
    }
  }
  summary.final_cost = cost;
  writeBack();
  return summary;
}

SchurLevenbergMarquardt::Summary SchurLevenbergMarquardt::solve(int max_iterations) {
  if (residuals_.empty()) return Summary{};
  return Solver(*this).run(max_iterations);
}

}  // namespace beslam::orb::optimize
