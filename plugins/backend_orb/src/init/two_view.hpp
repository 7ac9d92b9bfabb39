// Two-view initialisation: a homography and a fundamental matrix estimated in parallel by RANSAC
// (the same 8-point samples), each scored by a truncated chi-square sum; the homography is chosen when
// S_H / (S_H + S_F) > 0.40. The chosen model is decomposed into motion hypotheses (4 for the essential
// matrix, those of cv::decomposeHomographyMat for H), each checked by triangulating the inliers
// (cheirality, reprojection, parallax); one hypothesis must be clearly ahead of the others.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "beslam_orb/options.hpp"

namespace beslam::orb {

struct TwoViewOptions {
  int iterations = 200;
  double sigma = 1.0;
  double min_parallax_deg = 1.0;
  int min_triangulated = 50;
  double homography_ratio = 0.40;
  uint64_t seed = 42;
};

struct TwoViewResult {
  Eigen::Matrix3d R21 = Eigen::Matrix3d::Identity();  // camera 1 -> camera 2
  Eigen::Vector3d t21 = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> points;  // per keypoint of view 1 (camera-1 frame)
  std::vector<bool> triangulated;       // per keypoint of view 1
  bool used_homography = false;
  double score_h = 0, score_f = 0;
  int n_triangulated = 0;
};

class TwoViewInitializer {
 public:
  TwoViewInitializer(const Camera& camera, const TwoViewOptions& options);
  // matches12[i1] = i2 or -1. Returns true with a reconstruction, false to wait for another frame.
  bool reconstruct(const std::vector<cv::KeyPoint>& kps1, const std::vector<cv::KeyPoint>& kps2,
                   const std::vector<int>& matches12, TwoViewResult& result);

  // Building blocks, public for tests.
  static Eigen::Matrix3d homographyDLT(const std::vector<Eigen::Vector2d>& p1, const std::vector<Eigen::Vector2d>& p2);
  static Eigen::Matrix3d fundamental8(const std::vector<Eigen::Vector2d>& p1, const std::vector<Eigen::Vector2d>& p2);
  static Eigen::Vector3d triangulate(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2,
                                     const Eigen::Matrix<double, 3, 4>& P1, const Eigen::Matrix<double, 3, 4>& P2);

 private:
  struct Match {
    int i1, i2;
  };
  // Fits a model to each RANSAC set of the normalised matches (fit returns its score, < 0 to skip) and keeps
  // the best-scoring model and its inliers.
  template <typename Fit>
  void bestOverSets(const std::vector<Eigen::Vector2d>& n1, const std::vector<Eigen::Vector2d>& n2, Fit fit,
                    std::vector<bool>& inliers, double& score, Eigen::Matrix3d& model) const;
  void findHomography(std::vector<bool>& inliers, double& score, Eigen::Matrix3d& H21) const;
  void findFundamental(std::vector<bool>& inliers, double& score, Eigen::Matrix3d& F21) const;
  // Runs check(x1, x2, score) on every match (homogeneous pixels in images 1 and 2; it adds to the score
  // and says whether the match is an inlier); returns the score.
  template <class Check>
  double scoreMatches(std::vector<bool>& inliers, Check check) const;
  double checkHomography(const Eigen::Matrix3d& H21, const Eigen::Matrix3d& H12, std::vector<bool>& inliers) const;
  double checkFundamental(const Eigen::Matrix3d& F21, std::vector<bool>& inliers) const;
  bool reconstructF(const std::vector<bool>& inliers, const Eigen::Matrix3d& F21, TwoViewResult& r) const;
  bool reconstructH(const std::vector<bool>& inliers, const Eigen::Matrix3d& H21, TwoViewResult& r) const;
  int checkRT(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const std::vector<bool>& inliers, double th2,
              std::vector<Eigen::Vector3d>& points, std::vector<bool>& good, double& parallax_deg) const;

  Camera camera_;
  Eigen::Matrix3d K_;
  TwoViewOptions options_;
  // Both views' matched keypoints, Hartley-normalised (n = T * p), shared by the H and F searches.
  void normaliseMatches(std::vector<Eigen::Vector2d>& n1, Eigen::Matrix3d& T1, std::vector<Eigen::Vector2d>& n2,
                        Eigen::Matrix3d& T2) const;
  const std::vector<cv::KeyPoint>* kps1_ = nullptr;
  const std::vector<cv::KeyPoint>* kps2_ = nullptr;
  std::vector<Match> matches_;
  std::vector<std::vector<int>> sets_;
};

}  // namespace beslam::orb
