// The monocular map's scale from metric 3D boxes of cars, before anyone knows which cars are parked.
//
// A parked car j seen in frames k at metric centre b_k (camera frame) while the camera has pose
// (R_k, t_k) in map units satisfies R_k b_k + s t_k = p_j for one world point p_j and the map's metre
// factor s. Per track a weighted linear least squares gives (s_j, p_j), its standard error and its fit
// (chi-square per degree of freedom, with the box noise sigma(r) = sigma0 + sigma_per_m * r). A moving car
// either fits badly or fits a different s (a car keeping pace with the ego: s (1 - v_car / v_ego)), so the
// map's s is the largest cluster of well-determined, well-fitting tracks agreeing within `agreement`; it
// needs `min_tracks` of them and no rival cluster as large. Deterministic; no randomness.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

namespace beslam::orb {

struct ParkedCarScaleOptions {
  int min_observations = 8;          // frames a track needs
  double sigma0 = 0.1;               // m: box centre noise at range 0
  double sigma_per_m = 0.02;         // m per metre of range
  double max_chi2 = 4.0;             // per degree of freedom: a worse fit is not a parked car
  double max_relative_error = 0.03;  // standard error of s_j / s_j at most this
  double agreement = 0.03;           // tracks within this share of each other count as one cluster
  int min_tracks = 3;
  double max_range = 40.0;  // m: farther boxes are too noisy
};

struct ParkedCarScaleEstimate {
  double scale = 1;    // metres per map unit
  int tracks = 0;      // in the winning cluster
  int candidates = 0;  // well-determined, well-fitting tracks
};

class ParkedCarScale {
 public:
  explicit ParkedCarScale(const ParkedCarScaleOptions& options = {}) : options_(options) {}
  // One frame: its pose (map units) and the metric centres of the car boxes that carry a track id.
  void addFrame(const Eigen::Isometry3d& T_world_cam,
                const std::vector<std::pair<int32_t, Eigen::Vector3d>>& centres_cam);
  std::optional<ParkedCarScaleEstimate> estimate() const;
  // The map's unit changed by s (Map::rescale): stored camera positions follow.
  void rescale(double s);
  void clear() { tracks_.clear(); }
  void debugPrint(int64_t frame) const;  // one line per track with its fit (developers, BESLAM_ORB_DEBUG)

  struct Observation {
    Eigen::Matrix3d R_wc;
    Eigen::Vector3d t_wc, b_cam;
  };

 private:
  ParkedCarScaleOptions options_;
  std::map<int32_t, std::vector<Observation>> tracks_;
};

}  // namespace beslam::orb
