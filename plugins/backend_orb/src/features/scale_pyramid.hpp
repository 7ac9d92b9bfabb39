// Per-level scale factors of the image pyramid and the reprojection-error variances they imply.
#pragma once

#include <cmath>
#include <vector>

namespace beslam::orb {

struct ScalePyramid {
  int levels = 8;
  double factor = 1.2;
  double log_factor = std::log(1.2);
  std::vector<double> scale, inv_scale, sigma2, inv_sigma2;  // scale[l] = factor^l, sigma2 = scale^2

  ScalePyramid() = default;
  ScalePyramid(int n, double f) : levels(n), factor(f), log_factor(std::log(f)) {
    for (int l = 0; l < n; ++l) {
      const double s = std::pow(f, l);
      scale.push_back(s);
      inv_scale.push_back(1.0 / s);
      sigma2.push_back(s * s);
      inv_sigma2.push_back(1.0 / (s * s));
    }
  }
};

}  // namespace beslam::orb
