// The camera blackout: the images of chosen frames all black.
#include <algorithm>

#include "beslam/common/error.hpp"
#include "beslam/datasets/dataset.hpp"

namespace beslam::datasets {
namespace {

class BlackedOutDataset final : public Dataset {
 public:
  BlackedOutDataset(std::unique_ptr<Dataset> inner, std::vector<FrameRange> ranges)
      : inner_(std::move(inner)), ranges_(std::move(ranges)) {}
  std::string describe() const override { return inner_->describe() + ", black frames " + frameRangesText(ranges_); }
  std::size_t size() const override { return inner_->size(); }
  Frame load(std::size_t i) const override {
    Frame frame = inner_->load(i);
    if (black(frame.index)) {
      if (!frame.gray.empty()) frame.gray = cv::Mat::zeros(frame.gray.size(), frame.gray.type());
      if (!frame.color.empty()) frame.color = cv::Mat::zeros(frame.color.size(), frame.color.type());
    }
    return frame;
  }
  const Camera& camera() const override { return inner_->camera(); }
  std::optional<Eigen::Isometry3d> T_cam_lidar() const override { return inner_->T_cam_lidar(); }
  std::optional<trajectory::Trajectory> groundTruth() const override { return inner_->groundTruth(); }
  std::string labelPath() const override { return inner_->labelPath(); }
  std::optional<double> cameraHeight() const override { return inner_->cameraHeight(); }
  std::int64_t frameNumber(std::size_t i) const override { return inner_->frameNumber(i); }

 private:
  bool black(std::int64_t index) const {
    return std::any_of(ranges_.begin(), ranges_.end(), [&](const FrameRange& r) { return r.contains(index); });
  }
  std::unique_ptr<Dataset> inner_;
  std::vector<FrameRange> ranges_;
};

}  // namespace

std::unique_ptr<Dataset> blackOut(std::unique_ptr<Dataset> dataset, const std::vector<FrameRange>& ranges) {
  const std::size_t n = dataset->size();
  for (const FrameRange& r : ranges) {
    bool holds = false;
    for (std::size_t i = 0; i < n && !holds; ++i) {
      const std::int64_t f = dataset->frameNumber(i);
      holds = r.contains(f);
    }
    if (!holds)
      throw Error(
          "range " + frameRangesText({r}) + " holds none of the " + std::to_string(n) + " selected frames (" +
          (n ? "numbers " + std::to_string(dataset->frameNumber(0)) + ".." + std::to_string(dataset->frameNumber(n - 1))
             : std::string("none")) +
          ")");
  }
  return std::make_unique<BlackedOutDataset>(std::move(dataset), ranges);
}

}  // namespace beslam::datasets
