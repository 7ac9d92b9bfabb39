#include "beslam/eval/eval.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/formats/align.hpp"

namespace beslam::eval {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

std::string formatNumber(double value, const char* format = "%.9g") {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Inverse of a rigid transform through the transpose of its rotation, as evo's se3_inverse
// (KITTI rotations are kept as written, so this is not the same as a general matrix inverse).
Eigen::Matrix4d inverseRigid(const Eigen::Matrix4d& T_a_b) {
  Eigen::Matrix4d T_b_a = Eigen::Matrix4d::Identity();
  T_b_a.topLeftCorner<3, 3>() = T_a_b.topLeftCorner<3, 3>().transpose();
  T_b_a.topRightCorner<3, 1>() = -T_b_a.topLeftCorner<3, 3>() * T_a_b.topRightCorner<3, 1>();
  return T_b_a;
}

void appendErrors(const Eigen::Matrix4d& E, PoseErrors& errors, bool with_trans) {
  if (with_trans) errors.trans.push_back(E.topRightCorner<3, 1>().norm());
  errors.rot.push_back(rotationAngleRad(E.topLeftCorner<3, 3>()) * kRadToDeg);
  errors.full.push_back((E - Eigen::Matrix4d::Identity()).norm());
}

void requireSameSize(const Trajectory& ref, const Trajectory& est) {
  if (ref.size() != est.size()) {
    throw Error("trajectories are not paired: reference has " + std::to_string(ref.size()) + " poses, estimate " +
                std::to_string(est.size()));
  }
  if (ref.empty()) throw Error("no pose pairs to evaluate");
}

// Index j of the smallest |stamps_[j] - stamp| (the first one on ties, like numpy.argmin).
class NearestStamp {
 public:
  explicit NearestStamp(std::vector<double> stamps) : stamps_(std::move(stamps)) {
    sorted_ = std::is_sorted(stamps_.begin(), stamps_.end());
  }

  std::size_t operator()(double stamp) const {
    if (!sorted_) {
      std::size_t best = 0;
      for (std::size_t j = 1; j < stamps_.size(); ++j) {
        if (std::abs(stamps_[j] - stamp) < std::abs(stamps_[best] - stamp)) best = j;
      }
      return best;
    }
    // |s - stamp| does not increase up to the first s >= stamp and does not decrease after it.
    const auto right = std::lower_bound(stamps_.begin(), stamps_.end(), stamp);
    const std::size_t p = static_cast<std::size_t>(right - stamps_.begin());
    if (p == 0) return 0;
    std::size_t left = p - 1;
    const double left_diff = std::abs(stamps_[left] - stamp);
    while (left > 0 && std::abs(stamps_[left - 1] - stamp) == left_diff) --left;
    if (p == stamps_.size()) return left;
    return left_diff <= std::abs(stamps_[p] - stamp) ? left : p;
  }

  double stamp(std::size_t j) const { return stamps_[j]; }

 private:
  std::vector<double> stamps_;
  bool sorted_ = false;
};

Trajectory subset(const Trajectory& trajectory, const std::vector<std::size_t>& indices) {
  Trajectory out;
  out.stamps.reserve(indices.size());
  out.poses.reserve(indices.size());
  for (std::size_t i : indices) out.push_back(trajectory.stamps[i], trajectory.poses[i]);
  return out;
}

nlohmann::ordered_json statisticsJson(const Statistics& s) {
  nlohmann::ordered_json j;
  j["rmse"] = s.rmse;
  j["mean"] = s.mean;
  j["median"] = s.median;
  j["std"] = s.std;
  j["min"] = s.min;
  j["max"] = s.max;
  return j;
}

nlohmann::ordered_json metricJson(const MetricStatistics& m) {
  nlohmann::ordered_json j;
  j["trans"] = statisticsJson(m.trans);
  j["rot"] = statisticsJson(m.rot);
  j["full"] = statisticsJson(m.full);
  return j;
}

}  // namespace

std::string toString(AlignmentType type) {
  static const char* const kNames[] = {"none", "se3", "sim3"};  // in AlignmentType's order
  return kNames[static_cast<int>(type)];
}

AlignmentType parseAlignmentType(const std::string& name) {
  if (name == "none") return AlignmentType::kNone;
  if (name == "se3") return AlignmentType::kSe3;
  if (name == "sim3") return AlignmentType::kSim3;
  throw Error("unknown alignment '" + name + "' (expected none, se3 or sim3)");
}

PairedTrajectories associateByTime(const Trajectory& ref, const Trajectory& est, double max_diff,
                                   double est_time_offset) {
  if (ref.stamps.size() != ref.size() || est.stamps.size() != est.size()) {
    throw Error("cannot associate: a trajectory has fewer stamps than poses");
  }
  // Like evo: the poses of the shorter trajectory look up their nearest stamp in the longer one
  // (the estimate's stamps shifted by the offset); on equal sizes the estimate is the shorter one.
  const bool est_longer = est.size() > ref.size();
  const Trajectory& shorter = est_longer ? ref : est;
  const Trajectory& longer = est_longer ? est : ref;
  const double longer_offset = est_longer ? est_time_offset : -est_time_offset;

  std::vector<double> longer_stamps = longer.stamps;
  for (double& stamp : longer_stamps) stamp += longer_offset;
  const NearestStamp nearest(std::move(longer_stamps));

  std::vector<std::size_t> short_indices, long_indices;
  if (!longer.empty()) {
    for (std::size_t i = 0; i < shorter.size(); ++i) {
      const std::size_t j = nearest(shorter.stamps[i]);
      if (std::abs(nearest.stamp(j) - shorter.stamps[i]) <= max_diff) {
        short_indices.push_back(i);
        long_indices.push_back(j);
      }
    }
  }
  if (short_indices.empty()) {
    throw Error("no timestamps match within the max. difference " + formatNumber(max_diff, "%g") + " s (time offset " +
                formatNumber(est_time_offset, "%g") + " s)");
  }
  PairedTrajectories paired;
  paired.ref_indices = est_longer ? short_indices : long_indices;
  paired.est_indices = est_longer ? long_indices : short_indices;
  paired.ref = subset(ref, paired.ref_indices);
  paired.est = subset(est, paired.est_indices);
  return paired;
}

PairedTrajectories pairByIndex(const Trajectory& ref, const Trajectory& est) {
  if (ref.size() != est.size()) {
    throw Error("pose counts differ: reference " + std::to_string(ref.size()) + ", estimate " +
                std::to_string(est.size()) + " (files without timestamps pair by index)");
  }
  PairedTrajectories paired;
  paired.ref = ref;
  paired.est = est;
  paired.ref_indices.resize(ref.size());
  std::iota(paired.ref_indices.begin(), paired.ref_indices.end(), std::size_t{0});
  paired.est_indices = paired.ref_indices;
  return paired;
}

Alignment computeAlignment(const Trajectory& ref, const Trajectory& est, AlignmentType type, std::size_t first_n) {
  requireSameSize(ref, est);
  Alignment alignment;
  alignment.type = type;
  if (type == AlignmentType::kNone) return alignment;

  const std::size_t n = (first_n == 0 || first_n > ref.size()) ? ref.size() : first_n;
  alignment.poses_used = n;
  std::vector<Eigen::Vector3d> p_ref, p_est;
  for (std::size_t i = 0; i < n; ++i) {
    p_ref.push_back(ref.poses[i].translation());
    p_est.push_back(est.poses[i].translation());
  }
  const formats::Similarity fit = formats::umeyama(p_ref, p_est, n, type == AlignmentType::kSim3);
  alignment.scale = fit.scale;
  alignment.R_ref_est = fit.R_ref_est;
  alignment.t_ref_est = fit.t_ref_est;
  return alignment;
}

Trajectory applyAlignment(const Trajectory& est, const Alignment& alignment) {
  Eigen::Matrix4d T_ref_est = Eigen::Matrix4d::Identity();
  T_ref_est.topLeftCorner<3, 3>() = alignment.R_ref_est;
  T_ref_est.topRightCorner<3, 1>() = alignment.t_ref_est;
  Trajectory aligned;
  aligned.stamps = est.stamps;
  aligned.poses.reserve(est.size());
  for (const Eigen::Isometry3d& T_est_cam : est.poses) {
    Eigen::Matrix4d T_scaled = T_est_cam.matrix();
    T_scaled.topRightCorner<3, 1>() *= alignment.scale;
    Eigen::Isometry3d T_ref_cam;
    T_ref_cam.matrix() = T_ref_est * T_scaled;
    aligned.poses.push_back(T_ref_cam);
  }
  return aligned;
}

double rotationAngleRad(const Eigen::Matrix3d& R) {
  // Markley, "Unit quaternion from rotation matrix" (2008): build the quaternion from the largest of
  // the diagonal entries and the trace, then normalise. Robust for every angle and, unlike
  // acos((trace - 1) / 2), accurate for small angles and for slightly non-orthonormal input.
  const double decision[4] = {R(0, 0), R(1, 1), R(2, 2), R.trace()};
  const int choice = static_cast<int>(std::max_element(decision, decision + 4) - decision);
  Eigen::Vector4d q;  // x, y, z, w
  if (choice == 3) {
    q << R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1), 1.0 + decision[3];
  } else {
    const int i = choice, j = (i + 1) % 3, k = (j + 1) % 3;
    q(i) = 1.0 - decision[3] + 2.0 * R(i, i);
    q(j) = R(j, i) + R(i, j);
    q(k) = R(k, i) + R(i, k);
    q(3) = R(k, j) - R(j, k);
  }
  q.normalize();
  return 2.0 * std::atan2(q.head<3>().norm(), std::abs(q(3)));
}

PoseErrors absolutePoseErrors(const Trajectory& ref, const Trajectory& est) {
  requireSameSize(ref, est);
  PoseErrors errors;
  errors.trans.reserve(ref.size());
  errors.rot.reserve(ref.size());
  errors.full.reserve(ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const Eigen::Matrix4d& T_world_ref = ref.poses[i].matrix();
    const Eigen::Matrix4d& T_world_est = est.poses[i].matrix();
    errors.trans.push_back((T_world_est.topRightCorner<3, 1>() - T_world_ref.topRightCorner<3, 1>()).norm());
    appendErrors(inverseRigid(T_world_est) * T_world_ref, errors, false);
  }
  return errors;
}

PoseErrors relativePoseErrors(const Trajectory& ref, const Trajectory& est, std::size_t delta, bool all_pairs) {
  requireSameSize(ref, est);
  if (delta == 0) throw Error("RPE delta must be at least 1 frame");
  if (ref.size() <= delta) {
    throw Error("RPE with delta " + std::to_string(delta) + " needs more than " + std::to_string(delta) +
                " pose pairs, have " + std::to_string(ref.size()));
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  if (all_pairs) {
    for (std::size_t i = 0; i + delta < ref.size(); ++i) pairs.emplace_back(i, i + delta);
  } else {
    for (std::size_t i = 0; i + delta < ref.size(); i += delta) pairs.emplace_back(i, i + delta);
  }
  PoseErrors errors;
  for (const auto& [i, j] : pairs) {
    const Eigen::Matrix4d T_refi_refj = inverseRigid(ref.poses[i].matrix()) * ref.poses[j].matrix();
    const Eigen::Matrix4d T_esti_estj = inverseRigid(est.poses[i].matrix()) * est.poses[j].matrix();
    appendErrors(inverseRigid(T_refi_refj) * T_esti_estj, errors, true);
  }
  return errors;
}

Statistics computeStatistics(const std::vector<double>& errors) {
  if (errors.empty()) throw Error("no error values to summarise");
  Statistics s;
  s.count = errors.size();
  const double n = static_cast<double>(errors.size());
  double sum = 0.0, sum_squares = 0.0;
  for (double e : errors) {
    sum += e;
    sum_squares += e * e;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_squares / n);
  double sum_deviations = 0.0;
  for (double e : errors) sum_deviations += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(sum_deviations / n);  // population std, numpy's default
  const auto [min_it, max_it] = std::minmax_element(errors.begin(), errors.end());
  s.min = *min_it;
  s.max = *max_it;
  std::vector<double> sorted = errors;
  const std::size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid), sorted.end());
  s.median = sorted[mid];
  if (sorted.size() % 2 == 0) {
    const double below = *std::max_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid));
    s.median = (below + s.median) / 2.0;
  }
  return s;
}

bool EvalOptions::isValid(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (!format.empty() && format != "kitti" && format != "tum") {
    return fail("--format must be kitti or tum, not '" + format + "'");
  }
  if (!(max_diff >= 0.0) || !std::isfinite(max_diff)) return fail("--max-diff must be a finite number >= 0");
  if (!std::isfinite(est_time_offset)) return fail("--offset must be a finite number");
  if (delta < 1) return fail("--delta must be at least 1");
  return true;
}

EvalResult evaluatePaired(const Trajectory& ref, const Trajectory& est, const EvalOptions& options) {
  std::string problem;
  if (!options.isValid(&problem)) throw Error(problem);
  requireSameSize(ref, est);
  EvalResult result;
  result.pairs = ref.size();
  result.format = options.format;
  result.alignment = computeAlignment(ref, est, options.alignment, options.align_first_n);
  const Trajectory aligned = applyAlignment(est, result.alignment);

  const PoseErrors ape = absolutePoseErrors(ref, aligned);
  result.ape = {computeStatistics(ape.trans), computeStatistics(ape.rot), computeStatistics(ape.full)};
  const PoseErrors rpe = relativePoseErrors(ref, aligned, options.delta, options.all_pairs);
  result.rpe = {computeStatistics(rpe.trans), computeStatistics(rpe.rot), computeStatistics(rpe.full)};
  return result;
}

EvalResult evaluateFiles(const std::string& ref_path, const std::string& est_path, const EvalOptions& options) {
  std::string problem;
  if (!options.isValid(&problem)) throw Error(problem);
  const std::string format = options.format.empty() ? trajectory::detectFormat(ref_path) : options.format;
  const Trajectory ref = trajectory::read(ref_path, format);
  const Trajectory est = trajectory::read(est_path, format);

  PairedTrajectories paired;
  if (format == "tum") {
    try {
      paired = associateByTime(ref, est, options.max_diff, options.est_time_offset);
    } catch (const Error& e) {
      throw Error(est_path + ": " + e.what() + " of the reference " + ref_path);
    }
  } else {
    if (ref.size() != est.size()) {
      throw Error(est_path + ": has " + std::to_string(est.size()) + " poses but the reference " + ref_path + " has " +
                  std::to_string(ref.size()) + " (KITTI files pair by index)");
    }
    paired = pairByIndex(ref, est);
  }
  try {
    EvalResult result = evaluatePaired(paired.ref, paired.est, options);
    result.format = format;
    return result;
  } catch (const Error& e) {
    throw Error(ref_path + " vs " + est_path + ": " + e.what());
  }
}

std::string formatTable(const EvalResult& result) {
  std::ostringstream out;
  const Alignment& a = result.alignment;
  out << "pairs: " << result.pairs;
  if (!result.format.empty()) out << " (" << (result.format == "tum" ? "TUM, by timestamp" : "KITTI, by index") << ")";
  out << "\nalignment: " << toString(a.type);
  if (a.type != AlignmentType::kNone) {
    out << " on " << a.poses_used << " poses, scale " << formatNumber(a.scale) << "\n  rotation:";
    for (int r = 0; r < 3; ++r) {
      out << (r == 0 ? " [" : "; ");
      for (int c = 0; c < 3; ++c) out << (c == 0 ? "" : " ") << formatNumber(a.R_ref_est(r, c));
    }
    out << "]\n  translation: [" << formatNumber(a.t_ref_est.x()) << ' ' << formatNumber(a.t_ref_est.y()) << ' '
        << formatNumber(a.t_ref_est.z()) << "]";
  }
  out << "\n";
  char line[256];
  std::snprintf(line, sizeof(line), "%-15s %15s %15s %15s %15s %15s %15s\n", "metric", "rmse", "mean", "median", "std",
                "min", "max");
  out << line;
  auto row = [&](const char* name, const Statistics& s) {
    std::snprintf(line, sizeof(line), "%-15s %15.9g %15.9g %15.9g %15.9g %15.9g %15.9g\n", name, s.rmse, s.mean,
                  s.median, s.std, s.min, s.max);
    out << line;
  };
  row("APE trans (m)", result.ape.trans);
  row("APE rot (deg)", result.ape.rot);
  row("APE full", result.ape.full);
  row("RPE trans (m)", result.rpe.trans);
  row("RPE rot (deg)", result.rpe.rot);
  row("RPE full", result.rpe.full);
  return out.str();
}

std::string toJson(const EvalResult& result, int indent) {
  nlohmann::ordered_json j;
  j["pairs"] = result.pairs;
  nlohmann::ordered_json alignment;
  alignment["type"] = toString(result.alignment.type);
  alignment["scale"] = result.alignment.scale;
  nlohmann::ordered_json rotation = nlohmann::ordered_json::array();
  for (int r = 0; r < 3; ++r) {
    rotation.push_back(
        {result.alignment.R_ref_est(r, 0), result.alignment.R_ref_est(r, 1), result.alignment.R_ref_est(r, 2)});
  }
  alignment["rotation"] = rotation;
  alignment["translation"] = {result.alignment.t_ref_est.x(), result.alignment.t_ref_est.y(),
                              result.alignment.t_ref_est.z()};
  j["alignment"] = alignment;
  j["ape"] = metricJson(result.ape);
  j["rpe"] = metricJson(result.rpe);
  return j.dump(indent);
}

}  // namespace beslam::eval
