// A synthetic image sequence with exact ground truth: a camera driving down a textured box corridor
// (walls, floor, ceiling, end wall). Seen from inside a convex box every pixel sees one face, so
// rendering is one perspective warp per face, no depth test.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "beslam_orb/orb_slam.hpp"
#include "test_util.hpp"

namespace beslam::orb::test {

class CorridorWorld {
 public:
  static constexpr double kPxPerMetre = 60.0;
  CorridorWorld() {
    // origin, axis a, axis b (metres) and size; texture pixel (i, j) -> origin + i/ppm a + j/ppm b.
    addFace({-3, -2, -5}, {0, 0, 1}, {0, 1, 0}, 70, 3.5, 11);  // left wall
    addFace({3, -2, -5}, {0, 0, 1}, {0, 1, 0}, 70, 3.5, 12);   // right wall
    addFace({-3, 1.5, -5}, {0, 0, 1}, {1, 0, 0}, 70, 6, 13);   // floor
    addFace({-3, -2, -5}, {0, 0, 1}, {1, 0, 0}, 70, 6, 14);    // ceiling
    addFace({-3, -2, 65}, {1, 0, 0}, {0, 1, 0}, 6, 3.5, 15);   // end wall
  }

  Camera camera() const { return {640, 480, 500, 500, 320, 240}; }

  // Camera-to-world pose of frame i: forward 0.4 m per frame, a gentle weave and yaw.
  Eigen::Isometry3d pose(int i) const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    const double z = 0.4 * i;
    T.translation() = Eigen::Vector3d(0.6 * std::sin(0.08 * i), 0.1 * std::sin(0.05 * i), z);
    T.linear() = Eigen::AngleAxisd(0.08 * std::cos(0.08 * i), Eigen::Vector3d::UnitY()).toRotationMatrix();
    return T;
  }

  // A LiDAR scan of frame i in its camera frame: the faces sampled every `spacing` metres from 1 to
  // `max_ahead` metres ahead of the camera (seen from inside a convex box, every sample is visible).
  Eigen::Matrix3Xf lidarScan(int i, double spacing = 0.08, double max_ahead = 30.0) const {
    const Eigen::Isometry3d T_cw = pose(i).inverse();
    std::vector<Eigen::Vector3f> points;
    for (const Face& f : faces_) {
      const double la = f.texture.cols / kPxPerMetre, lb = f.texture.rows / kPxPerMetre;
      for (double a = 0; a <= la; a += spacing)
        for (double b = 0; b <= lb; b += spacing) {
          const Eigen::Vector3d p_cam = T_cw * (f.origin + a * f.a + b * f.b);
          if (p_cam.z() >= 1.0 && p_cam.z() <= max_ahead) points.push_back(p_cam.cast<float>());
        }
    }
    Eigen::Matrix3Xf scan(3, static_cast<Eigen::Index>(points.size()));
    for (size_t j = 0; j < points.size(); ++j) scan.col(static_cast<Eigen::Index>(j)) = points[j];
    return scan;
  }

  // Distance (metres) of a world point inside the corridor to its nearest face.
  double distanceToSurface(const Eigen::Vector3d& p_world) const {
    double d = 1e9;
    for (const Face& f : faces_) d = std::min(d, std::abs(f.a.cross(f.b).normalized().dot(p_world - f.origin)));
    return d;
  }

  cv::Mat render(int i) const {
    const Camera c = camera();
    const Eigen::Isometry3d T_cw = pose(i).inverse();
    Eigen::Matrix3d K;
    K << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1;
    cv::Mat image(c.height, c.width, CV_8UC1, cv::Scalar(0));
    for (const Face& f : faces_) {
      // Keep the part of the face in front of the camera: cut along axis a where depth < 0.3 m.
      int i0 = 0;
      const Eigen::Vector3d za = T_cw.linear().row(2).transpose();
      const double da = za.dot(f.a) / kPxPerMetre;
      double corner_depth = 1e9;
      for (double jb : {0.0, static_cast<double>(f.texture.rows)})
        corner_depth = std::min(corner_depth, (T_cw * (f.origin + f.b * jb / kPxPerMetre)).z());
      if (da > 1e-9 && corner_depth < 0.3) i0 = static_cast<int>((0.3 - corner_depth) / da) + 1;
      if (i0 >= f.texture.cols) continue;
      if (da <= 1e-9 && corner_depth < 0.3) continue;
      const cv::Mat tex = f.texture.colRange(i0, f.texture.cols);
      const Eigen::Vector3d o = f.origin + f.a * (i0 / kPxPerMetre);
      Eigen::Matrix3d H;
      H.col(0) = K * (T_cw.linear() * f.a / kPxPerMetre);
      H.col(1) = K * (T_cw.linear() * f.b / kPxPerMetre);
      H.col(2) = K * (T_cw * o);
      cv::Mat Hcv(3, 3, CV_64F);
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) Hcv.at<double>(r, k) = H(r, k);
      cv::Mat warped, mask;
      cv::warpPerspective(tex, warped, Hcv, image.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
      cv::warpPerspective(cv::Mat(tex.size(), CV_8UC1, cv::Scalar(255)), mask, Hcv, image.size(), cv::INTER_NEAREST,
                          cv::BORDER_CONSTANT);
      warped.copyTo(image, mask);
    }
    return image;
  }

 private:
  struct Face {
    Eigen::Vector3d origin, a, b;
    cv::Mat texture;
  };
  void addFace(Eigen::Vector3d origin, Eigen::Vector3d a, Eigen::Vector3d b, double la, double lb, uint64_t seed) {
    faces_.push_back(
        {origin, a, b, texturedImage(static_cast<int>(la * kPxPerMetre), static_cast<int>(lb * kPxPerMetre), seed)});
  }
  std::vector<Face> faces_;
};

}  // namespace beslam::orb::test
