// The car prior the plugin ships (plugins/reconstructor_sdf/data/car_shape_prior.bsdf), loaded once for the
// tests that fit or measure with it.
#pragma once

#include <string>

#include "shape/shape_prior.hpp"

namespace beslam::recon::test {

inline const shape::ShapePrior& shippedPrior() {
  static const shape::ShapePrior prior =
      shape::ShapePrior::load(std::string(BESLAM_SOURCE_DIR) + "/plugins/reconstructor_sdf/data/car_shape_prior.bsdf");
  return prior;
}

}  // namespace beslam::recon::test
