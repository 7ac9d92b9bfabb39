#include "beslam/eval/eval.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "beslam/common/error.hpp"
#include "test_support.hpp"

using beslam::Error;
using beslam::trajectory::Trajectory;
using namespace beslam::eval;
using beslam::eval::test::helix;

namespace {

constexpr double kDeg = 180.0 / M_PI;

// The estimate of `ref` seen from a frame where p_ref = s * R_ref_est * p_est + t_ref_est.
Trajectory inEstimateFrame(const Trajectory& ref, double s, const Eigen::Matrix3d& R_ref_est,
                           const Eigen::Vector3d& t_ref_est) {
  Trajectory est;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    Eigen::Isometry3d T_est_cam = Eigen::Isometry3d::Identity();
    T_est_cam.linear() = R_ref_est.transpose() * ref.poses[i].linear();
    T_est_cam.translation() = R_ref_est.transpose() * (ref.poses[i].translation() - t_ref_est) / s;
    est.push_back(ref.stamps[i], T_est_cam);
  }
  return est;
}

Trajectory withStamps(const std::vector<double>& stamps) {
  Trajectory t;
  for (double s : stamps) t.push_back(s, Eigen::Isometry3d::Identity());
  return t;
}

void expectAllNear(const std::vector<double>& values, double expected, double tolerance) {
  ASSERT_FALSE(values.empty());
  for (std::size_t i = 0; i < values.size(); ++i) EXPECT_NEAR(values[i], expected, tolerance) << "index " << i;
}

void expectRelative(double actual, double expected, const char* what) {
  EXPECT_NEAR(actual, expected, 1e-6 * std::abs(expected)) << what;
}

// evo's four RMSE figures: APE and RPE, translation and rotation.
void expectEvoRmse(const EvalResult& r, double ape_trans, double ape_rot, double rpe_trans, double rpe_rot) {
  expectRelative(r.ape.trans.rmse, ape_trans, "APE trans RMSE");
  expectRelative(r.ape.rot.rmse, ape_rot, "APE rot RMSE");
  expectRelative(r.rpe.trans.rmse, rpe_trans, "RPE trans RMSE");
  expectRelative(r.rpe.rot.rmse, rpe_rot, "RPE rot RMSE");
}

// Declares `var`, the shared evo data folder, or skips the test where it is absent.
#define REQUIRE_EVO_DATA(var)                               \
  const std::string var = beslam::eval::test::evoDataDir(); \
  if (var.empty()) GTEST_SKIP() << "shared evo data (" << BESLAM_SHARED_DATA << "/evo) not found"

const Eigen::Matrix3d kR_ref_est =
    (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized())).toRotationMatrix();
const Eigen::Vector3d kt_ref_est(12.0, -3.5, 0.25);

}  // namespace

// --- evo reference figures (/work/shared/data/README.md) ---------------------------------------------

TEST(EvoReference, Kitti00OrbSim3) {
  REQUIRE_EVO_DATA(dir);
  EvalOptions options;
  options.alignment = AlignmentType::kSim3;
  const EvalResult r = evaluateFiles(dir + "/KITTI_00_gt.txt", dir + "/KITTI_00_ORB.txt", options);
  EXPECT_EQ(r.pairs, 4541u);
  EXPECT_EQ(r.format, "kitti");
  expectEvoRmse(r, 0.937709074, 0.756300514, 0.027822453, 0.114973521);
  EXPECT_EQ(r.ape.trans.count, 4541u);
  EXPECT_EQ(r.rpe.trans.count, 4540u);
}

TEST(EvoReference, Freiburg1XyzOrbKeyframesSim3) {
  REQUIRE_EVO_DATA(dir);
  EvalOptions options;
  options.alignment = AlignmentType::kSim3;
  options.max_diff = 0.01;
  const EvalResult r =
      evaluateFiles(dir + "/freiburg1_xyz-groundtruth.txt", dir + "/freiburg1_xyz-ORB_kf_mono.txt", options);
  EXPECT_EQ(r.pairs, 32u);
  EXPECT_EQ(r.format, "tum");
  expectEvoRmse(r, 0.009754582, 2.371823868, 0.013834918, 0.884848960);
}

TEST(EvoReference, RotationAngleMustComeFromTheQuaternionNotFromTheTrace) {
  // KITTI rotations are printed with 7-9 digits, so they are slightly non-orthonormal; evo's angle
  // (through scipy's quaternion) differs from acos((trace - 1) / 2) by percents for small angles.
  REQUIRE_EVO_DATA(dir);
  const Trajectory ref = beslam::trajectory::readKitti(dir + "/KITTI_00_gt.txt");
  const Trajectory est = beslam::trajectory::readKitti(dir + "/KITTI_00_ORB.txt");
  const Trajectory aligned = applyAlignment(est, computeAlignment(ref, est, AlignmentType::kSim3));
  double sum_acos = 0.0;
  for (std::size_t i = 0; i + 1 < ref.size(); ++i) {
    const Eigen::Matrix3d R = (ref.poses[i].linear().transpose() * ref.poses[i + 1].linear()).transpose() *
                              (aligned.poses[i].linear().transpose() * aligned.poses[i + 1].linear());
    const double angle = std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0)) * kDeg;
    sum_acos += angle * angle;
  }
  const double rmse_acos = std::sqrt(sum_acos / static_cast<double>(ref.size() - 1));
  EXPECT_GT(std::abs(rmse_acos - 0.114973521), 1e-3);  // the trace route misses evo's figure
}

// --- alignment ---------------------------------------------------------------------------------------

TEST(Alignment, Sim3RecoversKnownTransformAndScaleAndZeroesErrors) {
  const Trajectory ref = helix(60);
  const Trajectory est = inEstimateFrame(ref, 0.4, kR_ref_est, kt_ref_est);
  const Alignment a = computeAlignment(ref, est, AlignmentType::kSim3);
  EXPECT_NEAR(a.scale, 0.4, 1e-12);
  EXPECT_TRUE(a.R_ref_est.isApprox(kR_ref_est, 1e-12));
  EXPECT_TRUE(a.t_ref_est.isApprox(kt_ref_est, 1e-12));
  EXPECT_EQ(a.poses_used, 60u);

  EvalOptions options;
  options.alignment = AlignmentType::kSim3;
  const EvalResult r = evaluatePaired(ref, est, options);
  EXPECT_LT(r.ape.trans.max, 1e-10);
  EXPECT_LT(r.ape.rot.max, 1e-6);
  EXPECT_LT(r.ape.full.max, 1e-10);
  EXPECT_LT(r.rpe.trans.max, 1e-10);
  EXPECT_LT(r.rpe.rot.max, 1e-6);
}

TEST(Alignment, Se3KeepsScaleAndNoneIsIdentity) {
  const Trajectory ref = helix(60);
  const Trajectory rigid = inEstimateFrame(ref, 1.0, kR_ref_est, kt_ref_est);
  const Alignment se3 = computeAlignment(ref, rigid, AlignmentType::kSe3);
  EXPECT_EQ(se3.scale, 1.0);
  EXPECT_TRUE(se3.R_ref_est.isApprox(kR_ref_est, 1e-12));
  EXPECT_TRUE(se3.t_ref_est.isApprox(kt_ref_est, 1e-12));

  // A scaled copy cannot be fitted without scale: se3 leaves error, sim3 removes it.
  const Trajectory scaled = inEstimateFrame(ref, 2.0, kR_ref_est, kt_ref_est);
  EvalOptions options;
  options.alignment = AlignmentType::kSe3;
  EXPECT_GT(evaluatePaired(ref, scaled, options).ape.trans.rmse, 0.1);
  options.alignment = AlignmentType::kSim3;
  EXPECT_LT(evaluatePaired(ref, scaled, options).ape.trans.rmse, 1e-10);

  const Alignment none = computeAlignment(ref, scaled, AlignmentType::kNone);
  EXPECT_EQ(none.scale, 1.0);
  EXPECT_TRUE(none.R_ref_est.isIdentity());
  EXPECT_TRUE(none.t_ref_est.isZero());
}

TEST(Alignment, FirstNPosesOnly) {
  const Trajectory ref = helix(60);
  Trajectory est = inEstimateFrame(ref, 3.0, kR_ref_est, kt_ref_est);
  for (std::size_t i = 20; i < est.size(); ++i) est.poses[i].translation().x() += 1.0;  // later drift
  const Alignment first = computeAlignment(ref, est, AlignmentType::kSim3, 20);
  EXPECT_EQ(first.poses_used, 20u);
  EXPECT_NEAR(first.scale, 3.0, 1e-12);
  EXPECT_TRUE(first.t_ref_est.isApprox(kt_ref_est, 1e-12));
  const Alignment all = computeAlignment(ref, est, AlignmentType::kSim3);
  EXPECT_GT(std::abs(all.scale - 3.0), 1e-3);
}

TEST(Alignment, DegenerateOrUnpairedInputThrows) {
  Trajectory same;
  for (int i = 0; i < 5; ++i) same.push_back(i, Eigen::Isometry3d::Identity());
  EXPECT_THROW(computeAlignment(same, same, AlignmentType::kSim3), Error);
  EXPECT_THROW(computeAlignment(helix(5), helix(6), AlignmentType::kSe3), Error);
  EXPECT_THROW(computeAlignment(Trajectory(), Trajectory(), AlignmentType::kSe3), Error);
}

// --- APE / RPE definitions -----------------------------------------------------------------------------

TEST(PoseErrors, ConstantWorldOffsetGivesKnownApeAndZeroRpe) {
  const Trajectory ref = helix(40);
  Trajectory est = ref;
  for (auto& T_world_cam : est.poses) T_world_cam.translation() += Eigen::Vector3d(0.3, 0.0, 0.4);
  const PoseErrors ape = absolutePoseErrors(ref, est);
  expectAllNear(ape.trans, 0.5, 1e-12);
  expectAllNear(ape.rot, 0.0, 1e-9);
  expectAllNear(ape.full, 0.5, 1e-12);
  const PoseErrors rpe = relativePoseErrors(ref, est);
  EXPECT_EQ(rpe.trans.size(), 39u);
  expectAllNear(rpe.trans, 0.0, 1e-12);
  expectAllNear(rpe.full, 0.0, 1e-12);

  const Statistics s = computeStatistics(ape.trans);
  EXPECT_NEAR(s.rmse, 0.5, 1e-12);
  EXPECT_NEAR(s.mean, 0.5, 1e-12);
  EXPECT_NEAR(s.median, 0.5, 1e-12);
  EXPECT_NEAR(s.std, 0.0, 1e-12);
}

TEST(PoseErrors, ConstantCameraRotationGivesKnownAngle) {
  const double angle = 5.0 / kDeg;
  const Trajectory ref = helix(30);
  Trajectory est = ref;
  const Eigen::Matrix3d R_cam_cam2 = Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  for (auto& T_world_cam : est.poses) T_world_cam.linear() = T_world_cam.linear() * R_cam_cam2;
  const PoseErrors ape = absolutePoseErrors(ref, est);
  expectAllNear(ape.rot, 5.0, 1e-10);
  expectAllNear(ape.trans, 0.0, 1e-12);
  expectAllNear(ape.full, 2.0 * std::sqrt(1.0 - std::cos(angle)), 1e-12);  // |R - I|_F
}

TEST(PoseErrors, RpeOfDoubledScaleIsTheReferenceStep) {
  // E = Q_rel^-1 P_rel with P_rel = [R_rel | 2 t_rel]: its translation is R_rel^T t_rel, as long as t_rel.
  const Trajectory ref = helix(25);
  Trajectory est = ref;
  for (auto& T_world_cam : est.poses) T_world_cam.translation() *= 2.0;
  const PoseErrors rpe = relativePoseErrors(ref, est);
  ASSERT_EQ(rpe.trans.size(), 24u);
  for (std::size_t i = 0; i + 1 < ref.size(); ++i) {
    const double step = (ref.poses[i + 1].translation() - ref.poses[i].translation()).norm();
    EXPECT_NEAR(rpe.trans[i], step, 1e-12);
    EXPECT_NEAR(rpe.rot[i], 0.0, 1e-6);
  }
}

TEST(PoseErrors, RpeDeltaPairsLikeEvo) {
  const Trajectory ref = helix(10);
  EXPECT_EQ(relativePoseErrors(ref, ref, 1).trans.size(), 9u);
  EXPECT_EQ(relativePoseErrors(ref, ref, 3).trans.size(), 3u);        // (0,3) (3,6) (6,9)
  EXPECT_EQ(relativePoseErrors(ref, ref, 4).trans.size(), 2u);        // (0,4) (4,8)
  EXPECT_EQ(relativePoseErrors(ref, ref, 4, true).trans.size(), 6u);  // (0,4) ... (5,9)
  EXPECT_THROW(relativePoseErrors(ref, ref, 10), Error);
  EXPECT_THROW(relativePoseErrors(ref, ref, 0), Error);
  EXPECT_THROW(absolutePoseErrors(ref, helix(9)), Error);
}

TEST(PoseErrors, RotationAngleOverTheWholeRange) {
  const Eigen::Vector3d axes[] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
                                  Eigen::Vector3d(1, -2, 3).normalized()};
  for (const Eigen::Vector3d& axis : axes) {
    for (double angle : {0.0, 1e-9, 1e-4, 0.3, M_PI / 2, 2.5, M_PI - 1e-6, M_PI}) {
      const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
      EXPECT_NEAR(rotationAngleRad(R), angle, 1e-12 + 1e-12 * angle) << "axis " << axis.transpose();
      EXPECT_NEAR(rotationAngleRad(R.transpose()), angle, 1e-12 + 1e-12 * angle);
    }
  }
}

TEST(PoseErrors, StatisticsLikeNumpy) {
  const Statistics even = computeStatistics({4.0, 1.0, 3.0, 2.0});
  EXPECT_DOUBLE_EQ(even.mean, 2.5);
  EXPECT_DOUBLE_EQ(even.median, 2.5);
  EXPECT_DOUBLE_EQ(even.std, std::sqrt(1.25));  // population std (ddof = 0)
  EXPECT_DOUBLE_EQ(even.rmse, std::sqrt(7.5));
  EXPECT_EQ(even.min, 1.0);
  EXPECT_EQ(even.max, 4.0);
  EXPECT_EQ(even.count, 4u);
  EXPECT_EQ(computeStatistics({3.0, 1.0, 2.0}).median, 2.0);
  EXPECT_EQ(computeStatistics({7.0}).std, 0.0);
  EXPECT_THROW(computeStatistics({}), Error);
}

// --- association -----------------------------------------------------------------------------------------

TEST(Association, NearestStampWithinMaxDiffAcrossGaps) {
  std::vector<double> ref_stamps;
  for (int i = 0; i <= 10; ++i) ref_stamps.push_back(0.1 * i);
  const Trajectory ref = withStamps(ref_stamps);
  const Trajectory est = withStamps({0.002, 0.1049, 0.35, 0.7, 0.9901, 5.0});  // 0.35 and 5.0 in gaps
  const PairedTrajectories p = associateByTime(ref, est, 0.01);
  EXPECT_EQ(p.ref_indices, (std::vector<std::size_t>{0, 1, 7, 10}));
  EXPECT_EQ(p.est_indices, (std::vector<std::size_t>{0, 1, 3, 4}));
  ASSERT_EQ(p.ref.size(), 4u);
  ASSERT_EQ(p.est.size(), 4u);
  EXPECT_EQ(p.ref.stamps[2], ref_stamps[7]);
  EXPECT_EQ(p.est.stamps[2], 0.7);
  // A tighter tolerance drops the pairs further apart than it.
  EXPECT_EQ(associateByTime(ref, est, 0.005).est_indices, (std::vector<std::size_t>{0, 1, 3}));
}

TEST(Association, LongerEstimateLooksUpFromTheReference) {
  const PairedTrajectories p = associateByTime(withStamps({0.0, 1.0}), withStamps({0.0, 0.5, 0.999, 2.0}), 0.01);
  EXPECT_EQ(p.ref_indices, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(p.est_indices, (std::vector<std::size_t>{0, 2}));
}

TEST(Association, TimeOffsetIsAddedToEstimateStamps) {
  std::vector<double> ref_stamps, est_stamps;
  for (int i = 0; i < 11; ++i) {
    ref_stamps.push_back(0.1 * i);
    est_stamps.push_back(0.1 * i + 3.0);
  }
  const Trajectory ref = withStamps(ref_stamps), est = withStamps(est_stamps);
  EXPECT_THROW(associateByTime(ref, est, 0.01), Error);
  EXPECT_EQ(associateByTime(ref, est, 0.01, -3.0).ref.size(), 11u);
  // Same when the estimate is the longer one.
  est_stamps.push_back(99.0);
  EXPECT_EQ(associateByTime(ref, withStamps(est_stamps), 0.01, -3.0).ref.size(), 11u);
}

TEST(Association, TiesGoToTheEarlierPoseAndUnsortedStampsWork) {
  EXPECT_EQ(associateByTime(withStamps({1.0, 1.5}), withStamps({1.25}), 0.3).ref_indices, std::vector<std::size_t>{0});
  EXPECT_EQ(associateByTime(withStamps({1.25}), withStamps({1.0, 1.5, 3.0}), 0.3).est_indices,
            std::vector<std::size_t>{0});
  EXPECT_EQ(associateByTime(withStamps({1.0, 1.0, 2.0}), withStamps({1.0}), 0.0).ref_indices,
            std::vector<std::size_t>{0});
  const PairedTrajectories unsorted = associateByTime(withStamps({0.5, 0.1, 0.3}), withStamps({0.29, 0.11}), 0.02);
  EXPECT_EQ(unsorted.ref_indices, (std::vector<std::size_t>{2, 1}));
  EXPECT_EQ(unsorted.est_indices, (std::vector<std::size_t>{0, 1}));
}

TEST(Association, PairByIndexNeedsEqualSizes) {
  EXPECT_EQ(pairByIndex(helix(5), helix(5)).est_indices, (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  EXPECT_THROW(pairByIndex(helix(5), helix(4)), Error);
}

// --- files and report --------------------------------------------------------------------------------------

using EvalFiles = beslam::eval::test::ScratchDir;

TEST_F(EvalFiles, KittiSizeMismatchNamesBothFiles) {
  beslam::trajectory::writeKitti(path("ref.txt"), helix(10));
  beslam::trajectory::writeKitti(path("est.txt"), helix(9));
  try {
    evaluateFiles(path("ref.txt"), path("est.txt"), EvalOptions());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path("est.txt") + ": has 9 poses", 0), 0u) << message;
    EXPECT_NE(message.find(path("ref.txt") + " has 10"), std::string::npos) << message;
  }
}

TEST_F(EvalFiles, MalformedEstimateNamesFileAndLine) {
  beslam::trajectory::writeTum(path("ref.tum"), helix(10));
  write("est.tum", "100 0 0 0 0 0 0 1\n100.1 0 0 nan 0 0 0 1\n");
  try {
    evaluateFiles(path("ref.tum"), path("est.tum"), EvalOptions());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path("est.tum") + ":2: ", 0), 0u) << e.what();
  }
}

TEST_F(EvalFiles, TumFilesAreAssociatedThenEvaluated) {
  const Trajectory ref = helix(50, 1000.0);
  Trajectory est = inEstimateFrame(ref, 0.5, kR_ref_est, kt_ref_est);
  for (double& stamp : est.stamps) stamp += 0.003;  // within max_diff
  Trajectory thinned;                               // keep every second pose
  for (std::size_t i = 0; i < est.size(); i += 2) thinned.push_back(est.stamps[i], est.poses[i]);
  beslam::trajectory::writeTum(path("ref.tum"), ref);
  beslam::trajectory::writeTum(path("est.tum"), thinned);
  EvalOptions options;
  options.alignment = AlignmentType::kSim3;
  const EvalResult r = evaluateFiles(path("ref.tum"), path("est.tum"), options);
  EXPECT_EQ(r.pairs, 25u);
  EXPECT_EQ(r.format, "tum");
  EXPECT_NEAR(r.alignment.scale, 0.5, 1e-9);
  EXPECT_LT(r.ape.trans.max, 1e-9);
  EXPECT_LT(r.rpe.trans.max, 1e-9);

  options.max_diff = 0.001;
  EXPECT_THROW(evaluateFiles(path("ref.tum"), path("est.tum"), options), Error);
}

TEST(Report, JsonHasExactlyTheDocumentedShape) {
  const Trajectory ref = helix(30);
  EvalOptions options;
  options.alignment = AlignmentType::kSim3;
  const EvalResult r = evaluatePaired(ref, inEstimateFrame(ref, 2.0, kR_ref_est, kt_ref_est), options);
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(toJson(r));
  std::vector<std::string> keys;
  for (const auto& item : j.items()) keys.push_back(item.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"pairs", "alignment", "ape", "rpe"}));
  EXPECT_EQ(j["pairs"], 30);
  const auto& a = j["alignment"];
  EXPECT_EQ(a.size(), 4u);
  EXPECT_EQ(a["type"], "sim3");
  EXPECT_NEAR(a["scale"].get<double>(), 2.0, 1e-12);
  ASSERT_EQ(a["rotation"].size(), 3u);
  for (int row = 0; row < 3; ++row) {
    ASSERT_EQ(a["rotation"][row].size(), 3u);
    for (int col = 0; col < 3; ++col) EXPECT_NEAR(a["rotation"][row][col].get<double>(), kR_ref_est(row, col), 1e-12);
  }
  ASSERT_EQ(a["translation"].size(), 3u);
  EXPECT_NEAR(a["translation"][0].get<double>(), kt_ref_est.x(), 1e-12);
  for (const char* metric : {"ape", "rpe"}) {
    EXPECT_EQ(j[metric].size(), 3u);
    for (const char* part : {"trans", "rot", "full"}) {
      std::vector<std::string> stat_keys;
      for (const auto& item : j[metric][part].items()) stat_keys.push_back(item.key());
      EXPECT_EQ(stat_keys, (std::vector<std::string>{"rmse", "mean", "median", "std", "min", "max"}))
          << metric << "." << part;
    }
  }
  EXPECT_EQ(j["ape"]["trans"]["rmse"].get<double>(), r.ape.trans.rmse);  // full precision survives

  const std::string table = formatTable(r);
  EXPECT_NE(table.find("pairs: 30"), std::string::npos) << table;
  EXPECT_NE(table.find("alignment: sim3"), std::string::npos) << table;
  EXPECT_NE(table.find("RPE rot (deg)"), std::string::npos) << table;
}

TEST(Options, ValidationNamesTheOption) {
  std::string error;
  EvalOptions options;
  EXPECT_TRUE(options.isValid(&error));
  options.max_diff = -1.0;
  EXPECT_FALSE(options.isValid(&error));
  EXPECT_NE(error.find("--max-diff"), std::string::npos);
  options = EvalOptions();
  options.format = "euroc";
  EXPECT_FALSE(options.isValid(&error));
  EXPECT_NE(error.find("--format"), std::string::npos);
  EXPECT_EQ(parseAlignmentType("sim3"), AlignmentType::kSim3);
  EXPECT_EQ(toString(AlignmentType::kSe3), "se3");
  EXPECT_THROW(parseAlignmentType("sim2"), Error);
}
