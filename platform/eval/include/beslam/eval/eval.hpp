// Trajectory evaluation: APE and RPE computed exactly as the `evo` package defines them.
// Contract (Q = reference poses T_world_cam, P = estimate after alignment, both paired pose by pose):
// - Pairing: KITTI files pair by index (equal sizes required). TUM files are associated by timestamp
//   like evo: every pose of the shorter trajectory takes the nearest stamp (est stamps + offset) of the
//   longer one, kept when |dt| <= max_diff; ties go to the earlier pose.
// - Alignment none / se3 / sim3 (Umeyama on positions): p_ref = s * R_ref_est * p_est + t_ref_est; an
//   aligned pose is [R_ref_est * R_i | s * R_ref_est * t_i + t_ref_est]. RPE uses the aligned estimate.
// - APE: E_i = P_i^-1 Q_i. RPE (delta frames, consecutive pairs i, i+delta, i+2 delta...):
//   E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j). Errors: trans = |t(E)| (m), rot = rotation angle of R(E) (deg,
//   through the unit quaternion as scipy does), full = Frobenius norm of E - I (4x4).
// - Statistics: rmse, mean, median, population std (numpy's default), min, max.
// - Failures throw beslam::Error with one line naming the file (or files) and the cause.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include "beslam/trajectory/trajectory.hpp"

namespace beslam::eval {

using trajectory::Trajectory;

enum class AlignmentType { kNone, kSe3, kSim3 };

// "none", "se3", "sim3".
std::string toString(AlignmentType type);
// Inverse of toString; throws beslam::Error on any other name.
AlignmentType parseAlignmentType(const std::string& name);

// The similarity that maps estimate positions into the reference frame (identity for kNone).
struct Alignment {
  AlignmentType type = AlignmentType::kNone;
  double scale = 1.0;
  Eigen::Matrix3d R_ref_est = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_ref_est = Eigen::Vector3d::Zero();
  std::size_t poses_used = 0;  // how many leading pose pairs fed the Umeyama fit
};

// Two trajectories of equal length, pose i of one belonging to pose i of the other.
struct PairedTrajectories {
  Trajectory ref;
  Trajectory est;
  std::vector<std::size_t> ref_indices;  // index into the original reference of each pair
  std::vector<std::size_t> est_indices;  // index into the original estimate of each pair
};

// evo's associate_trajectories(ref, est, max_diff, offset): throws beslam::Error when nothing matches.
PairedTrajectories associateByTime(const Trajectory& ref, const Trajectory& est, double max_diff,
                                   double est_time_offset = 0.0);
// Pose i with pose i; throws beslam::Error when the sizes differ.
PairedTrajectories pairByIndex(const Trajectory& ref, const Trajectory& est);

// Umeyama fit of the first `first_n` pairs (0 = all). Throws beslam::Error when the positions are
// degenerate (fewer than 2 non-zero singular values of the covariance, as evo) or too few.
Alignment computeAlignment(const Trajectory& ref, const Trajectory& est, AlignmentType type, std::size_t first_n = 0);
// The estimate expressed in the reference frame: scale its positions, then apply [R | t] on the left.
Trajectory applyAlignment(const Trajectory& est, const Alignment& alignment);

// Rotation angle in radians of a (nearly) orthonormal 3x3 matrix, the way evo obtains it through scipy:
// unit quaternion by Markley's method, angle = 2 atan2(|q_xyz|, |q_w|).
double rotationAngleRad(const Eigen::Matrix3d& R);

// One error value per pose (APE) or per pose pair (RPE).
struct PoseErrors {
  std::vector<double> trans;  // metres
  std::vector<double> rot;    // degrees
  std::vector<double> full;   // |E - I|_F, unitless
};

// Both need paired trajectories of equal size; throw beslam::Error otherwise.
PoseErrors absolutePoseErrors(const Trajectory& ref, const Trajectory& est);
// delta >= 1 frames; all_pairs false: pairs (0, d), (d, 2d), ...; true: (i, i + d) for every i.
PoseErrors relativePoseErrors(const Trajectory& ref, const Trajectory& est, std::size_t delta = 1,
                              bool all_pairs = false);

struct Statistics {
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0;
  std::size_t count = 0;
};
// Throws beslam::Error on an empty list.
Statistics computeStatistics(const std::vector<double>& errors);

struct EvalOptions {
  std::string format;  // "kitti", "tum", or "" to detect from the reference file
  AlignmentType alignment = AlignmentType::kNone;
  std::size_t align_first_n = 0;  // 0: fit the alignment on all pairs
  double max_diff = 0.01;         // s, TUM association only
  double est_time_offset = 0.0;   // s, added to the estimate's stamps (TUM only)
  std::size_t delta = 1;          // RPE frame delta
  bool all_pairs = false;         // RPE: every (i, i + delta) instead of consecutive pairs
  // True when the options are usable; otherwise false and *error names the bad option.
  bool isValid(std::string* error) const;
};

struct MetricStatistics {
  Statistics trans, rot, full;
};

struct EvalResult {
  std::size_t pairs = 0;
  std::string format;  // the format actually used
  Alignment alignment;
  MetricStatistics ape, rpe;
};

// Evaluates already paired trajectories.
EvalResult evaluatePaired(const Trajectory& ref, const Trajectory& est, const EvalOptions& options);
// Reads, pairs and evaluates two files; every error names the file(s) concerned.
EvalResult evaluateFiles(const std::string& ref_path, const std::string& est_path, const EvalOptions& options);

// Human-readable table (pairs, alignment, one row per metric with rmse mean median std min max).
std::string formatTable(const EvalResult& result);
// {"pairs": N, "alignment": {"type", "scale", "rotation" (3x3 rows), "translation"},
//  "ape": {"trans": S, "rot": S, "full": S}, "rpe": {...}}, S = {"rmse","mean","median","std","min","max"}.
std::string toJson(const EvalResult& result, int indent = 2);

// `beslam eval` (args exclude the program and "eval"):
//   --ref FILE --est FILE [--format kitti|tum] [--align none|se3|sim3] [--align-first N]
//   [--max-diff 0.01] [--offset 0] [--delta 1] [--all-pairs] [--json FILE] [--help]
// Prints the table to out. Returns 0 on success, 2 on a usage error, 1 on an input error; on failure
// prints exactly one line to err.
int runEvalCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace beslam::eval
