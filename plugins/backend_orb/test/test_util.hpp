// Shared helpers for the backend_orb tests: a synthetic textured image and KITTI paths.
#pragma once

#include <sys/stat.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

namespace beslam::orb::test {

// Grey image full of blurred random shapes: plenty of FAST corners, no repetition.
inline cv::Mat texturedImage(int width, int height, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat img(height, width, CV_8UC1, cv::Scalar(128));
  for (int i = 0; i < width * height / 400; ++i) {
    const cv::Point c(rng.uniform(0, width), rng.uniform(0, height));
    const int r = rng.uniform(3, 25);
    const cv::Scalar colour(rng.uniform(0, 256));
    if (rng.uniform(0, 2) == 0) {
      cv::circle(img, c, r, colour, cv::FILLED, cv::LINE_AA);
    } else {
      cv::RotatedRect rect(c, cv::Size2f(static_cast<float>(r * 2), static_cast<float>(r)), rng.uniform(0.f, 180.f));
      cv::Point2f v[4];
      rect.points(v);
      std::vector<cv::Point> pts(v, v + 4);
      cv::fillConvexPoly(img, pts, colour, cv::LINE_AA);
    }
  }
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  return img;
}

inline bool exists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

#ifdef BESLAM_SHARED_DATA
inline std::string sharedData() { return BESLAM_SHARED_DATA; }
#else
inline std::string sharedData() { return ""; }
#endif

}  // namespace beslam::orb::test
