#include "sample_frames.hpp"

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/pipeline/objects.hpp"

namespace beslam::pipeline::detail {

namespace {

const cv::Scalar kMoving(40, 40, 230);      // BGR red
const cv::Scalar kParked(60, 200, 60);      // green
const cv::Scalar kBackground(0, 215, 255);  // yellow
const cv::Scalar kUnknown(200, 200, 200);   // grey

cv::Scalar labelColour(uint16_t label) {
  if (label == BESLAM_LABEL_DYNAMIC) return kMoving;
  if (label >= BESLAM_LABEL_STATIC_BASE) return kParked;
  return kBackground;
}

}  // namespace

std::set<size_t> samplePositions(size_t frames, int count) {
  std::set<size_t> positions;
  if (frames == 0 || count <= 0) return positions;
  for (int k = 0; k < count; ++k)
    positions.insert(std::min(frames - 1, static_cast<size_t>((k + 0.5) * static_cast<double>(frames) / count)));
  return positions;
}

cv::Mat drawSampleFrame(const cv::Mat& image, const cv::Mat& labels, const std::vector<beslam_keypoint>& keypoints,
                        const std::vector<beslam_box3d>& boxes, const beslam_camera& camera) {
  cv::Mat drawn;
  if (image.channels() == 1)
    cv::cvtColor(image, drawn, cv::COLOR_GRAY2BGR);
  else
    drawn = image.clone();
  if (!labels.empty() && labels.size() == drawn.size()) {  // tint labelled pixels
    cv::Mat tint = drawn.clone();
    tint.setTo(kMoving, labels == BESLAM_LABEL_DYNAMIC);
    tint.setTo(kParked, labels >= BESLAM_LABEL_STATIC_BASE);
    cv::addWeighted(drawn, 0.6, tint, 0.4, 0, drawn);
  }
  for (const beslam_box3d& b : boxes) {
    double r[4];
    projectBox(b, camera, r);
    if (r[0] < 0) continue;
    const cv::Scalar colour = b.motion_state == BESLAM_MOTION_DYNAMIC  ? kMoving
                              : b.motion_state == BESLAM_MOTION_STATIC ? kParked
                                                                       : kUnknown;
    cv::rectangle(drawn, cv::Point2d(r[0], r[1]), cv::Point2d(r[2], r[3]), colour, 1, cv::LINE_AA);
    if (b.track_id >= 0)
      cv::putText(drawn, std::to_string(b.track_id), cv::Point2d(r[0] + 2, r[1] + 12), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                  colour, 1, cv::LINE_AA);
  }
  for (const beslam_keypoint& k : keypoints) {
    const cv::Point2f p(k.x, k.y);
    const cv::Scalar colour = labelColour(k.label);
    cv::circle(drawn, p, 2, colour, cv::FILLED, cv::LINE_AA);
    if (k.flags & BESLAM_KEYPOINT_MATCHED) cv::circle(drawn, p, 4, colour, 1, cv::LINE_AA);
  }
  // Legend.
  int x = 6;
  for (const auto& [name, colour] :
       {std::pair<const char*, cv::Scalar>{"moving", kMoving}, {"parked", kParked}, {"background", kBackground}}) {
    cv::circle(drawn, cv::Point(x + 4, 12), 4, colour, cv::FILLED, cv::LINE_AA);
    cv::putText(drawn, name, cv::Point(x + 12, 16), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(255, 255, 255), 1,
                cv::LINE_AA);
    x += 16 + 9 * static_cast<int>(std::string(name).size());
  }
  return drawn;
}

void writeSampleFrame(const std::string& path, const cv::Mat& drawn) {
  std::vector<uchar> jpeg;
  if (!cv::imencode(".jpg", drawn, jpeg, {cv::IMWRITE_JPEG_QUALITY, 85})) throwAt(path, "cannot encode sample frame");
  writeFileAtomic(path, std::string(jpeg.begin(), jpeg.end()));
}

}  // namespace beslam::pipeline::detail
