// The cars the shape prior learns from and is checked on, built by platform/sim's car generator.
//
// Contract
// - trainingCars(n, seed): shape class uniform over the five classes; (l, w, h) uniform over the
//   sequence range of the class widened on each side by 6 % of the range's midpoint; side-profile
//   fractions jittered (hb, x_wb, x_rf, x_rr by +-0.03, x_rb by +-0.02, then kept in order:
//   x_wb <= 0.5, x_rf <= x_wb - 0.02, -0.48 <= x_rr <= x_rf - 0.05, -0.5 <= x_rb <= x_rr - 0.01). The
//   sequences (`beslam synth`) never jitter the profile and draw inside the unwidened ranges.
// - heldOutCars(n, seed): what the sequences draw: class with their probabilities (sedan 30 %,
//   hatchback 22 %, wagon 18 %, suv 17 %, van 13 %), sizes in sim::sequenceSizeRange, default profiles;
//   from a random stream separate from trainingCars' for the same seed.
// - Meshes are in the object frame of shape/shape_prior.hpp (box centre origin, z up); size is the box
//   the sequences label: (l, w + 0.008, h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "shape/shape_prior.hpp"

namespace beslam::recon::tools {

struct Car {
  std::string shape;  // class name
  shape::TrainingShape body;
};

std::vector<Car> trainingCars(int n, std::uint64_t seed);
std::vector<Car> heldOutCars(int n, std::uint64_t seed);

std::vector<shape::TrainingShape> bodies(const std::vector<Car>& cars);

}  // namespace beslam::recon::tools

namespace beslam::recon::tools {

// Simulated surface observations of a car (object frame): up to n points on its exterior that the
// straight line from sensor_obj reaches unoccluded, plus isotropic Gaussian noise of noise_m.
std::vector<Eigen::Vector3d> visibleSurfacePoints(const shape::Mesh& mesh, const Eigen::Vector3d& sensor_obj, int n,
                                                  double noise_m, std::uint64_t seed);

}  // namespace beslam::recon::tools

namespace beslam::recon::tools {

// A simulated depth-map patch (object frame): rays from camera_obj through a cols x rows grid spanning
// the box as seen from the camera; those that hit the car, with their depth along the ray plus uniform-sum
// noise of standard deviation noise_m.
struct ObjectRay {
  Eigen::Vector3d direction;
  double depth;
};
std::vector<ObjectRay> depthPatch(const shape::Mesh& mesh, const Eigen::Vector3d& camera_obj,
                                  const Eigen::Vector3d& size, int cols, int rows, double noise_m, std::uint64_t seed);

}  // namespace beslam::recon::tools
