// Levenberg-Marquardt step control as Ceres' LevenbergMarquardtStrategy does it, shared by the backend's
// own solvers (local BA's SchurLevenbergMarquardt, the pose-only optimiser): the damped system is
// H + mu * clamp(diag H), a step is taken when it achieves more than kMinRelativeDecrease of the decrease
// the linear model predicts, then mu shrinks by Nielsen's rule; a refused step multiplies mu by a doubling
// nu. A solve ends on Ceres' function and parameter tolerances.
#pragma once

#include <algorithm>
#include <cmath>

namespace beslam::orb::optimize::lm {

constexpr double kMinDiagonal = 1e-6, kMaxDiagonal = 1e32;                                            // Ceres' defaults
constexpr double kFunctionTolerance = 1e-6, kParameterTolerance = 1e-8, kMinRelativeDecrease = 1e-3;  // Ceres'

inline double clampDiagonal(double d) { return std::min(std::max(d, kMinDiagonal), kMaxDiagonal); }

// Ceres' convergence tests on a candidate, before it is accepted (when true it is dropped and the solve
// ends): the step's norm against the parameters' norm, or a cost change too small to matter.
inline bool converged(double step_norm, double x_norm, double cost, double new_cost) {
  if (step_norm <= kParameterTolerance * (x_norm + kParameterTolerance)) return true;
  return std::isfinite(new_cost) && std::abs(cost - new_cost) <= kFunctionTolerance * std::abs(cost);
}

struct Damping {
  double mu = 1e-4, nu = 2;  // Ceres' initial trust region radius 1e4

  // After a step whose achieved over predicted decrease was rho (> kMinRelativeDecrease).
  void accepted(double rho) {
    mu *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
    nu = 2;
  }
  // After a refused step; false once the damping is past any use (the solve ends).
  bool refused() {
    mu *= nu;
    nu *= 2;
    return mu <= 1e32;
  }
};

}  // namespace beslam::orb::optimize::lm
