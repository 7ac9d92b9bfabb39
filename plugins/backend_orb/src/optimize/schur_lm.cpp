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

SchurLevenbergMarquardt::Summary SchurLevenbergMarquardt::solve(int max_iterations) {
  Summary summary;
  const int n_poses = static_cast<int>(poses_.size()), n_vectors = static_cast<int>(vectors_.size());
  if (residuals_.empty()) return summary;

  // Moving poses are the unknowns of the reduced system, in the order they were added.
  std::vector<int> slot(n_poses, -1);
  int n = 0;
  for (int k = 0; k < n_poses; ++k)
    if (!pose_fixed_[k]) slot[k] = n++;
  const int dim = 6 * n;

  // Residuals grouped by 3-vector (then pose, then the order given); per vector its moving poses (pairs).
  std::vector<int> order(residuals_.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return residuals_[a].vector != residuals_[b].vector ? residuals_[a].vector < residuals_[b].vector
                                                        : residuals_[a].pose < residuals_[b].pose;
  });
  std::vector<int> res_begin(n_vectors + 1, 0), pair_begin(n_vectors + 1, 0), pair_slot, res_pair(order.size(), -1);
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

  // Past kMaxDensePoses the reduced system is block-sparse: a 6 x 6 block for each pair of poses that share
  // a 3-vector (a global BA's covisibility), found once; each vector's pair (a, b >= a) names its block.
  const bool sparse = n > kMaxDensePoses;
  std::vector<std::pair<int, int>> block_pos;  // (row slot, column slot), column >= row, sorted
  std::vector<int> pair_block_begin, pair_block;
  if (sparse) {
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

  // Vector ranges of about equal residual counts.
  std::array<int, kRanges + 1> range_begin{};
  range_begin[kRanges] = n_vectors;
  for (int c = 1, v = 0; c < kRanges; ++c) {
    const long target = static_cast<long>(residuals_.size()) * c / kRanges;
    while (v < n_vectors && res_begin[v] < target) ++v;
    range_begin[c] = v;
  }

  // State: current and candidate copies (cost functions read them through params pointers).
  std::vector<double> pose_now(7 * n_poses), pose_try(7 * n_poses), vec_now(3 * n_vectors), vec_try(3 * n_vectors);
  for (int k = 0; k < n_poses; ++k) std::copy(poses_[k], poses_[k] + 7, &pose_now[7 * k]);
  for (int v = 0; v < n_vectors; ++v) std::copy(vectors_[v], vectors_[v] + 3, &vec_now[3 * v]);

  // The linearisation at the current state.
  std::vector<Eigen::Matrix3d> V(n_vectors), V_inv(n_vectors);
  std::vector<Eigen::Vector3d> gx(n_vectors), dx(n_vectors);
  std::vector<Matrix63> W(pair_slot.size());
  struct RangeSums {
    std::vector<Matrix6d> U;
    std::vector<Vector6d> gp;
    Eigen::MatrixXd S;               // upper blocks of sum W V^-1 W^T (dense)
    std::vector<Matrix6d> S_blocks;  // the same by block_pos (sparse)
    Eigen::VectorXd t;               // sum W V^-1 gx
    double cost = 0, predicted = 0;
  };
  std::array<RangeSums, kRanges> sums;
  std::vector<Matrix6d> U_total(n);
  std::vector<Vector6d> gp_total(n);
  for (RangeSums& s : sums) {
    s.U.assign(n, Matrix6d::Zero());
    s.gp.assign(n, Vector6d::Zero());
  }

  const auto residualCost = [&](const Residual& r, const double* pose, const double* vec) {
    double res[kMaxRows];
    const double* params[] = {pose, vec};
    r.cost->Evaluate(params, res, nullptr);
    double sq = 0;
    for (int i = 0; i < r.cost->num_residuals(); ++i) sq += res[i] * res[i];
    if (!r.loss) return 0.5 * sq;
    double rho[3];
    r.loss->Evaluate(sq, rho);
    return 0.5 * rho[0];
  };
  const auto costAt = [&](const std::vector<double>& pose, const std::vector<double>& vec) {
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
  };

  const auto linearise = [&]() {
    runRanges([&](int c) {
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
    });
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
  };

  double cost = linearise();
  summary.initial_cost = cost;
  summary.iterations = 1;
  lm::Damping damping;
  const double& mu = damping.mu;
  Eigen::MatrixXd S(sparse ? 0 : dim, sparse ? 0 : dim);
  Eigen::VectorXd b(dim), dp(dim);
  // Sparse: the upper triangle in a fixed pattern (one triplet per block entry, in block_pos order), its
  // fill-reducing ordering and symbolic factorisation computed once.
  Eigen::SparseMatrix<double> S_sparse(dim, dim);
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::AMDOrdering<int>> sparse_llt;
  bool analysed = false;
  std::vector<Eigen::Triplet<double>> triplets;
  for (int step = 0; step < max_iterations; ++step) {  // steps tried, successful or not (Ceres' iterations)
    // The damped reduced system.
    runRanges([&](int c) {
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
    });
    b.setZero();
    for (int k = 0; k < n; ++k) b.segment<6>(6 * k) = -gp_total[k];
    for (const RangeSums& s : sums) b += s.t;
    const auto dampedU = [&](int k) {
      Matrix6d U = U_total[k];
      for (int d = 0; d < 6; ++d) U(d, d) += mu * clampDiagonal(U(d, d));
      return U;
    };
    bool solved = dim == 0;
    if (dim > 0 && !sparse) {
      S.setZero();
      for (int k = 0; k < n; ++k) S.block<6, 6>(6 * k, 6 * k) = dampedU(k);
      for (const RangeSums& s : sums) S -= s.S;
      const Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> llt(S);
      if (llt.info() == Eigen::Success) {
        dp = llt.solve(b);
        solved = dp.allFinite();
      }
    } else if (dim > 0) {
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
      if (sparse_llt.info() == Eigen::Success) {
        dp = sparse_llt.solve(b);
        solved = dp.allFinite();
      }
    }
    double predicted = 0;
    if (solved) {
      // Gradient g = [gp; gx]; predicted decrease of the linear model 0.5 (-g.d + mu d.D.d) (Ceres' LM).
      for (int k = 0; k < n; ++k) {
        const Vector6d d = dp.segment<6>(6 * k);
        for (int i = 0; i < 6; ++i)
          predicted += 0.5 * (-gp_total[k](i) * d(i) + mu * clampDiagonal(U_total[k](i, i)) * d(i) * d(i));
      }
      runRanges([&](int c) {
        double part = 0;
        for (int v = range_begin[c]; v < range_begin[c + 1]; ++v) {
          Eigen::Vector3d rhs = -gx[v];
          for (int a = pair_begin[v]; a < pair_begin[v + 1]; ++a)
            rhs.noalias() -= W[a].transpose() * dp.segment<6>(6 * pair_slot[a]);
          dx[v] = V_inv[v] * rhs;
          for (int i = 0; i < 3; ++i)
            part += 0.5 * (-gx[v](i) * dx[v](i) + mu * clampDiagonal(V[v](i, i)) * dx[v](i) * dx[v](i));
        }
        sums[c].predicted = part;
      });
      for (const RangeSums& s : sums) predicted += s.predicted;
    }
    double new_cost = cost;
    if (solved && predicted > 0) {
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
      new_cost = costAt(pose_try, vec_try);
    }
    // Ceres' convergence tests, on the candidate before it is accepted: a step this small, or a cost change
    // this small, ends the solve where it is (the candidate is dropped).
    if (solved && predicted > 0) {
      double step_sq = dp.squaredNorm(), x_sq = 0;
      for (int v = 0; v < n_vectors; ++v)
        if (res_begin[v] < res_begin[v + 1]) step_sq += dx[v].squaredNorm();
      for (double x : pose_now) x_sq += x * x;
      for (double x : vec_now) x_sq += x * x;
      if (lm::converged(std::sqrt(step_sq), std::sqrt(x_sq), cost, new_cost)) break;
    }
    const double rho = solved && predicted > 0 ? (cost - new_cost) / predicted : -1;
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
  for (int k = 0; k < n_poses; ++k)
    if (slot[k] >= 0) std::copy(&pose_now[7 * k], &pose_now[7 * k] + 7, poses_[k]);
  for (int v = 0; v < n_vectors; ++v) std::copy(&vec_now[3 * v], &vec_now[3 * v] + 3, vectors_[v]);
  return summary;
}

}  // namespace beslam::orb::optimize
