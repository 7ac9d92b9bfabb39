// beslam::sim car meshes on their own: the procedural car body that `beslam synth` places in its
// sequences, for tools that learn or check shapes (the reconstructor's shape prior).
//
// Contract
// - carMesh(shape, l, w, h) returns the same triangles the sequences use for that shape and size
//   (World builds its cars with the same function), as an indexed triangle soup: three vertices per
//   face, in the renderer's order: the faces are NOT consistently oriented (the body and cabin wind
//   clockwise seen from outside; on one side the wheel rims disagree with their caps).
// - Frame: ISO vehicle frame, metres: x forward, y left, z up, origin at the bottom centre of the box,
//   so the mesh spans x in [-l/2, l/2], z in [0, h] and y in [-w/2 - 0.004, w/2 + 0.004] (the tyres
//   stand 4 mm proud of the body; the sequences' labelled width is w + 0.008).
// - The mesh is not watertight: the cabin has no floor (it stands on the body's top face) and the wheels
//   are separate prisms without an inner cap that overlap the body.
// - A CarProfile overrides the shape's side-profile fractions (of h and l); fractions outside
//   (0, 1) for hb or an x order other than x_rb < x_rr < x_rf < x_wb throw beslam::Error.
// - sequenceSizeRange(shape): the uniform (l, w, h) ranges the sequences draw each shape from.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace beslam::sim {

enum class CarShapeClass { Sedan, Hatchback, Suv, Van, Wagon };
constexpr int kCarShapeClasses = 5;

const char* carShapeName(CarShapeClass shape);  // "sedan", "hatchback", "suv", "van", "wagon"

// Side profile as fractions: body top hb (of h), windscreen base x_wb, roof front x_rf, roof rear x_rr,
// rear window base x_rb (of l, from the centre, forward positive).
struct CarProfile {
  double hb = 0.6, x_wb = 0.2, x_rf = 0.02, x_rr = -0.22, x_rb = -0.33;
};

CarProfile defaultCarProfile(CarShapeClass shape);

struct CarMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> faces;
};

CarMesh carMesh(CarShapeClass shape, double length, double width, double height, const CarProfile* profile = nullptr);

struct CarSizeRange {
  double l_min, l_max, w_min, w_max, h_min, h_max;
};
CarSizeRange sequenceSizeRange(CarShapeClass shape);

}  // namespace beslam::sim
