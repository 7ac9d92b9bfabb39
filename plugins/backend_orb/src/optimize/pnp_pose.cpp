#include "optimize/pnp_pose.hpp"

#include <Eigen/Core>  // before OpenCV's Eigen utilities
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <vector>

#include "map/camera_model.hpp"
#include "map/frame.hpp"
#include "map/map_point.hpp"

namespace beslam::orb {

int poseFromMatches(Frame& frame, const Camera& camera, const PnpOptions& options) {
  std::vector<cv::Point3f> p_world;
  std::vector<cv::Point2f> uv;
  std::vector<size_t> index;
  for (size_t i = 0; i < frame.size(); ++i) {
    const MapPoint* mp = frame.points[i];
    if (!mp) continue;
    p_world.emplace_back(static_cast<float>(mp->position.x()), static_cast<float>(mp->position.y()),
                         static_cast<float>(mp->position.z()));
    uv.push_back(frame.features->keypoints[i].pt);
    index.push_back(i);
  }
  cv::Mat K, rvec, tvec, inliers;
  cv::eigen2cv(intrinsics(camera), K);
  cv::setRNGSeed(static_cast<int>(options.seed));
  if (!cv::solvePnPRansac(p_world, uv, K, cv::Mat(), rvec, tvec, false, 300, options.threshold_px, 0.99, inliers,
                          options.epnp ? cv::SOLVEPNP_EPNP : cv::SOLVEPNP_ITERATIVE) ||
      inliers.rows < options.min_inliers)
    return -1;
  std::vector<bool> keep(index.size(), false);
  for (int r = 0; r < inliers.rows; ++r) keep[static_cast<size_t>(inliers.at<int>(r))] = true;
  for (size_t k = 0; k < index.size(); ++k)
    if (!keep[k]) frame.points[index[k]] = nullptr;
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d R_cw;
  Eigen::Vector3d t_cw;
  cv::cv2eigen(R, R_cw);
  cv::cv2eigen(tvec, t_cw);
  frame.T_cw = Eigen::Isometry3d::Identity();
  frame.T_cw.linear() = R_cw;
  frame.T_cw.translation() = t_cw;
  return inliers.rows;
}

}  // namespace beslam::orb
