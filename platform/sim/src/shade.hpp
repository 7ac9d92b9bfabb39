// Internal: procedural materials. Every function is pure: (material parameters, texture coordinates in
// metres, pixel footprint in metres) -> RGB in [0, 1]. Detail finer than the footprint fades out.
#pragma once

#include "world.hpp"

namespace beslam::sim::detail {

struct ShadeInput {
  std::uint16_t material;
  std::int32_t param;
  float u, v;       // metres
  float footprint;  // metres per pixel on the surface
};

Vec3f shadeSurface(const World& world, const ShadeInput& in);
Vec3f shadeSky(const Eigen::Vector3f& dir_sim);  // unit direction, z up
float lidarReflectance(std::uint16_t material);
float noiseTile(float u, float v);  // tileable value noise in [0, 1], period 1

}  // namespace beslam::sim::detail
