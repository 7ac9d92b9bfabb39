// The car prior against the simulator's cars: the generator's frame, training determinism with the real
// cars, and how well the shipped prior reconstructs held-out cars from the sequences' ranges.
#include <gtest/gtest.h>

#include "beslam/shape_prior/car_set.hpp"
#include "beslam/sim/car_mesh.hpp"
#include "shape/shape_prior.hpp"
#include "shipped_prior.hpp"

using namespace beslam::recon;

TEST(CarSet, MeshesAreCentredInTheirBox) {
  for (const auto& car : tools::heldOutCars(6, 3)) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
    for (const auto& v : car.body.mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
    EXPECT_LT((hi - car.body.size / 2).cwiseAbs().maxCoeff(), 1e-5) << car.shape;
    EXPECT_LT((lo + car.body.size / 2).head<2>().cwiseAbs().maxCoeff(), 1e-5) << car.shape;
    EXPECT_NEAR(lo.z(), -car.body.size.z() / 2, 0.03) << car.shape;  // octagonal wheels: 2.4-2.8 cm clear
    const shape::MeshDistance d(car.body.mesh);
    EXPECT_LT(d.solidSignedDistance(Eigen::Vector3d(0, 0, -0.2)), -0.15) << car.shape;                   // in the body
    EXPECT_LT(d.signedDistance(Eigen::Vector3d(-0.3, 0, car.body.size.z() / 2 - 0.1)), 0) << car.shape;  // cabin
    EXPECT_GT(d.signedDistance(Eigen::Vector3d(car.body.size.x() / 2 - 0.1, 0, car.body.size.z() / 2 - 0.1)), 0)
        << car.shape;  // above the bonnet
  }
  // Training and held-out cars come from different draws.
  EXPECT_NE(tools::trainingCars(1, 3)[0].body.size, tools::heldOutCars(1, 3)[0].body.size);
}

TEST(CarPrior, TrainingOnTheGeneratorsCarsIsDeterministic) {
  shape::TrainOptions opt;
  opt.grid = {16, 8, 8};
  opt.seed = 4;
  const auto cars = tools::bodies(tools::trainingCars(10, opt.seed));
  EXPECT_EQ(shape::trainShapePrior(cars, opt).serialise(), shape::trainShapePrior(cars, opt).serialise());
}

TEST(CarPrior, ShippedMeanCarIsACarInItsBox) {
  const shape::ShapePrior& prior = test::shippedPrior();
  const Eigen::Vector3d size(4.6, 1.8, 1.5);
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(prior.dimensions());
  EXPECT_LT(prior.distance(Eigen::Vector3d(0, 0, -0.2), size, z), -0.3);            // body
  EXPECT_LT(prior.distance(Eigen::Vector3d(-0.4, 0, 0.55), size, z), -0.05);        // cabin
  EXPECT_GT(prior.distance(Eigen::Vector3d(1.8, 0, 0.6), size, z), 0.2);            // above the bonnet
  EXPECT_NEAR(prior.distance(Eigen::Vector3d(3.3, 0, -0.2), size, z), 1.0, 0.05);   // 1 m in front
  EXPECT_NEAR(prior.distance(Eigen::Vector3d(0, -1.9, -0.2), size, z), 1.0, 0.05);  // 1 m to the right
  const shape::Mesh m = prior.mesh(z, size);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (const auto& v : m.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  EXPECT_LT((hi - size / 2).cwiseAbs().maxCoeff(), 0.06) << hi.transpose();
  EXPECT_LT((lo + size / 2).cwiseAbs().maxCoeff(), 0.06) << lo.transpose();
}

TEST(CarPrior, ShippedPriorReconstructsHeldOutCars) {
  const shape::ShapePrior& prior = test::shippedPrior();
  ASSERT_GE(prior.dimensions(), 2);
  ASSERT_LE(prior.dimensions(), 8);
  std::vector<double> chamfer;
  for (const auto& car : tools::heldOutCars(8, 11)) {
    const Eigen::VectorXd z = prior.project(prior.sampleGrid(car.body));
    chamfer.push_back(shape::chamferDistance(prior.mesh(z, car.body.size), car.body.mesh, 300, 5));
  }
  std::sort(chamfer.begin(), chamfer.end());
  // `beslam shape-prior eval` on 40 held-out cars measures a median of 4.7 mm and a maximum of 5.3 mm
  // (docs/reconstruction.md); the bounds leave room for the 300-sample estimate.
  EXPECT_LT(chamfer[chamfer.size() / 2], 0.02);
  EXPECT_LT(chamfer.back(), 0.04);
}
