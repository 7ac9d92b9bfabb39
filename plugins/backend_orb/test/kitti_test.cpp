// KITTI odometry 06 excerpt (51 frames, real data): initialises within 10 frames, tracks every frame
// after, APE (Sim(3) aligned translation RMSE) within 0.05 m. Skipped without the shared data.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "ape.hpp"
#include "beslam_orb/orb_slam.hpp"
#include "kitti.hpp"
#include "test_util.hpp"

namespace beslam::orb {
namespace {

TEST(Kitti06, TracksTheExcerptWithinTheApeBound) {
  const std::string data = test::sharedData();
  const std::string seq = data + "/kitti/odometry/sequences/06";
  if (data.empty() || !test::exists(seq + "/image_0/000000.png"))
    GTEST_SKIP() << "KITTI 06 excerpt not found (BESLAM_SHARED_DATA=" << data << "/kitti/odometry/sequences/06)";
  const auto gt = kitti::readPoses(data + "/kitti/odometry/poses/06.txt");
  const cv::Mat first = cv::imread(kitti::imagePath(seq, 0), cv::IMREAD_GRAYSCALE);
  OrbSlam slam(kitti::readCamera(seq + "/calib.txt", first.cols, first.rows), Options{});
  size_t n = 0;
  for (;; ++n) {
    const cv::Mat image = cv::imread(kitti::imagePath(seq, n), cv::IMREAD_GRAYSCALE);
    if (image.empty()) break;
    slam.track(image, cv::Mat(), 0.1 * static_cast<double>(n), static_cast<int64_t>(n));
  }
  slam.finish();
  ASSERT_EQ(n, 51u);
  const Statistics st = slam.statistics();
  EXPECT_GE(st.initialised_at_frame, 0);
  EXPECT_LE(st.initialised_at_frame, 10);
  EXPECT_EQ(st.resets, 0);
  const auto traj = slam.trajectory();
  // Every frame from the initialisation on is tracked.
  std::vector<bool> tracked(n, false);
  for (const FramePose& p : traj) tracked[p.frame_index] = true;
  for (size_t i = static_cast<size_t>(st.initialised_at_frame); i < n; ++i) EXPECT_TRUE(tracked[i]) << "frame " << i;
  std::vector<Eigen::Vector3d> est, ref;
  for (const FramePose& p : traj) {
    est.push_back(p.T_world_cam.translation());
    ref.push_back(gt[p.frame_index].translation());
  }
  const auto ape = eval::apeTranslation(est, ref);
  RecordProperty("ape_rmse_m", std::to_string(ape.rmse));
  EXPECT_LT(ape.rmse, 0.05) << "APE " << ape.rmse << " m over " << est.size() << " frames";
}

}  // namespace
}  // namespace beslam::orb
