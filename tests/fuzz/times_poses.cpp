// Timestamp and pose files of the dataset readers: KITTI odometry / image-folder times.txt, KITTI raw
// timestamps.txt, EuRoC's ground truth (state_groundtruth_estimate0/data.csv) and a KITTI pose file as
// selectPoses keeps it for the frames of a sequence. Bad files are one beslam::Error naming the file; what a
// reader accepts holds finite, strictly increasing times (a wrong time order gives a wrong APE, issue 54)
// and rigid poses.
#include <cmath>

#include "beslam/common/error.hpp"
#include "dataset_impl.hpp"
#include "fuzz_support.hpp"

namespace {

bool rigid(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear();
  return T.matrix().allFinite() && (R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-3) &&
         R.determinant() > 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace ds = beslam::datasets::detail;
  using beslam::fuzz::require;
  const std::string path = beslam::fuzz::writeScratch(data, size, "times.txt");
  beslam::fuzz::acceptErrors([&] {
    const std::vector<double> t = ds::readTimes(path);
    for (size_t i = 0; i < t.size(); ++i) {
      require(std::isfinite(t[i]), "times.txt: a time is not finite");
      require(i == 0 || t[i] > t[i - 1], "times.txt: times do not increase strictly");
    }
  });
  beslam::fuzz::acceptErrors([&] {
    const std::vector<long double> t = ds::readRawTimestamps(path);
    for (size_t i = 0; i < t.size(); ++i) {
      require(std::isfinite(t[i]), "timestamps.txt: a time is not finite");
      require(i == 0 || t[i] > t[i - 1], "timestamps.txt: times do not increase strictly");
    }
  });
  beslam::fuzz::acceptErrors([&] {
    const beslam::trajectory::Trajectory gt = ds::readEurocGroundTruth(path);
    for (size_t i = 0; i < gt.size(); ++i) {
      require(std::isfinite(gt.stamps[i]), "EuRoC ground truth: a time is not finite");
      require(i == 0 || gt.stamps[i] > gt.stamps[i - 1], "EuRoC ground truth: times do not increase strictly");
      require(rigid(gt.poses[i]), "EuRoC ground truth: a pose is not a rigid transform");
    }
  });
  beslam::fuzz::acceptErrors([&] {
    // A three-frame sequence whose frames 0 and 2 are selected.
    std::vector<ds::FrameEntry> frames(2);
    frames[0].index = 0;
    frames[1].index = 2;
    frames[1].timestamp = 0.2;
    const beslam::trajectory::Trajectory poses = ds::selectPoses(path, 3, frames);
    require(poses.size() == 2, "selectPoses: not one pose a selected frame");
    for (size_t i = 0; i < poses.size(); ++i)
      require(poses.poses[i].matrix().allFinite(), "selectPoses: a pose is not finite");
  });
  return 0;
}
