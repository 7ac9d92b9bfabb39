#include "scale/parked_car_scale.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace beslam::orb {

void ParkedCarScale::addFrame(const Eigen::Isometry3d& T_world_cam,
                              const std::vector<std::pair<int32_t, Eigen::Vector3d>>& centres_cam) {
  for (const auto& [id, b] : centres_cam) {
    if (id < 0 || !b.allFinite() || std::hypot(b.x(), b.z()) > options_.max_range) continue;
    tracks_[id].push_back({T_world_cam.linear(), T_world_cam.translation(), b});
  }
}

void ParkedCarScale::rescale(double s) {
  for (auto& [id, obs] : tracks_)
    for (Observation& o : obs) o.t_wc *= s;
}

namespace {

struct TrackFit {
  double s = 0, se = 0, chi2_dof = 0;
  bool solved = false;
};

using Observation = ParkedCarScale::Observation;

// One track's weighted least squares for (s, p).
TrackFit fitTrack(const std::vector<Observation>& obs, const ParkedCarScaleOptions& options_) {
  TrackFit fit;
  {
    // Unknowns x = (s, p): each frame gives 3 rows  t_k s - p = -R_k b_k, weighted by 1 / sigma(r_k)^2.
    Eigen::Matrix4d AtA = Eigen::Matrix4d::Zero();
    Eigen::Vector4d Aty = Eigen::Vector4d::Zero();
    for (const Observation& o : obs) {
      const double sigma = options_.sigma0 + options_.sigma_per_m * o.b_cam.norm();
      const double w = 1.0 / (sigma * sigma);
      Eigen::Matrix<double, 3, 4> A;
      A.col(0) = o.t_wc;
      A.rightCols<3>() = -Eigen::Matrix3d::Identity();
      const Eigen::Vector3d y = -(o.R_wc * o.b_cam);
      AtA += w * A.transpose() * A;
      Aty += w * A.transpose() * y;
    }
    const Eigen::FullPivLU<Eigen::Matrix4d> lu(AtA);
    if (lu.rank() < 4) return fit;  // the camera did not move: s is not observable
    const Eigen::Vector4d x = lu.solve(Aty);
    if (!(x[0] > 0)) return fit;
    double chi2 = 0;
    for (const Observation& o : obs) {
      const double sigma = options_.sigma0 + options_.sigma_per_m * o.b_cam.norm();
      chi2 += (o.R_wc * o.b_cam + x[0] * o.t_wc - x.tail<3>()).squaredNorm() / (sigma * sigma);
    }
    const double dof = 3.0 * static_cast<double>(obs.size()) - 4.0;
    fit.s = x[0];
    fit.se = std::sqrt(std::max(0.0, lu.inverse()(0, 0)));
    fit.chi2_dof = chi2 / dof;
    fit.solved = true;
  }
  return fit;
}

}  // namespace

void ParkedCarScale::debugPrint(int64_t frame) const {
  std::fprintf(stderr, "frame %ld parked-car scale:", static_cast<long>(frame));
  for (const auto& [id, obs] : tracks_) {
    if (static_cast<int>(obs.size()) < options_.min_observations) continue;
    const TrackFit f = fitTrack(obs, options_);
    if (f.solved) std::fprintf(stderr, " %d:%zu:s%.3f/se%.3f/c%.1f", id, obs.size(), f.s, f.se, f.chi2_dof);
  }
  std::fprintf(stderr, "\n");
}

std::optional<ParkedCarScaleEstimate> ParkedCarScale::estimate() const {
  struct Fit {
    double s, se;
  };
  std::vector<Fit> fits;
  for (const auto& [id, obs] : tracks_) {
    if (static_cast<int>(obs.size()) < options_.min_observations) continue;
    const TrackFit f = fitTrack(obs, options_);
    if (!f.solved || f.chi2_dof > options_.max_chi2 || f.se / f.s > options_.max_relative_error) continue;
    fits.push_back({f.s, f.se});
  }
  if (static_cast<int>(fits.size()) < options_.min_tracks) return std::nullopt;
  std::sort(fits.begin(), fits.end(), [](const Fit& a, const Fit& b) { return a.s < b.s; });
  // The largest cluster: for each fit, the fits within `agreement` of it (in log scale).
  int best = 0, best_at = -1, rival = 0;
  std::vector<int> counts(fits.size(), 0);
  for (size_t i = 0; i < fits.size(); ++i) {
    for (const Fit& f : fits) counts[i] += std::abs(std::log(f.s / fits[i].s)) <= options_.agreement;
    if (counts[i] > best) best = counts[i], best_at = static_cast<int>(i);
  }
  // A rival: a cluster as large, centred on a fit outside the winner's cluster.
  for (size_t i = 0; i < fits.size(); ++i)
    if (std::abs(std::log(fits[i].s / fits[best_at].s)) > 2 * options_.agreement) rival = std::max(rival, counts[i]);
  if (best < options_.min_tracks || rival >= best) return std::nullopt;
  // The winner: inverse-variance mean of its cluster.
  double num = 0, den = 0;
  for (const Fit& f : fits)
    if (std::abs(std::log(f.s / fits[best_at].s)) <= options_.agreement) {
      num += f.s / (f.se * f.se);
      den += 1.0 / (f.se * f.se);
    }
  return ParkedCarScaleEstimate{num / den, best, static_cast<int>(fits.size())};
}

}  // namespace beslam::orb
