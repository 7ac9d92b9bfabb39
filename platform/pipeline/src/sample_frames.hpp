// Sample frames (internal to the runner): a few frames spread over the run, drawn the way a reader of the
// paper looks at them. Pixels a mask labels dynamic are tinted red, static-object pixels green; the
// backend's features are dots: red on dynamic labels, green on static objects (parked cars), yellow on
// the background; a ring marks a feature matched to a map point. Written as samples/NNNNNN.jpg.
#pragma once

#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <vector>

#include "beslam/data.h"
#include "beslam/kinds/backend.h"

namespace beslam::pipeline::detail {

// `count` frame positions (0-based, into a range of `frames`) spread evenly, centred in equal parts.
std::set<size_t> samplePositions(size_t frames, int count);

// The drawn image (BGR). `image` is grey or BGR; `labels` a CV_16UC1 mask or empty.
cv::Mat drawSampleFrame(const cv::Mat& image, const cv::Mat& labels, const std::vector<beslam_keypoint>& keypoints,
                        const std::vector<beslam_box3d>& boxes, const beslam_camera& camera);

// Encodes `drawn` as JPEG and writes it atomically to `path`; throws beslam::Error naming the path.
void writeSampleFrame(const std::string& path, const cv::Mat& drawn);

}  // namespace beslam::pipeline::detail
