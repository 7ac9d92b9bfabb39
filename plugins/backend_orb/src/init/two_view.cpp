#include "init/two_view.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <future>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <random>

namespace beslam::orb {
namespace {

// Hartley normalisation: zero mean, unit mean absolute deviation per axis.
void normalise(const std::vector<Eigen::Vector2d>& p, std::vector<Eigen::Vector2d>& out, Eigen::Matrix3d& T) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& x : p) mean += x;
  mean /= static_cast<double>(p.size());
  Eigen::Vector2d dev = Eigen::Vector2d::Zero();
  for (const auto& x : p) dev += (x - mean).cwiseAbs();
  dev /= static_cast<double>(p.size());
  const double sx = dev.x() > 1e-12 ? 1.0 / dev.x() : 1.0, sy = dev.y() > 1e-12 ? 1.0 / dev.y() : 1.0;
  out.resize(p.size());
  for (size_t i = 0; i < p.size(); ++i) out[i] = {(p[i].x() - mean.x()) * sx, (p[i].y() - mean.y()) * sy};
  T << sx, 0, -mean.x() * sx, 0, sy, -mean.y() * sy, 0, 0, 1;
}

}  // namespace

void TwoViewInitializer::normaliseMatches(std::vector<Eigen::Vector2d>& n1, Eigen::Matrix3d& T1,
                                          std::vector<Eigen::Vector2d>& n2, Eigen::Matrix3d& T2) const {
  std::vector<Eigen::Vector2d> p1(matches_.size()), p2(matches_.size());
  for (size_t i = 0; i < matches_.size(); ++i) {
    p1[i] = {(*kps1_)[matches_[i].i1].pt.x, (*kps1_)[matches_[i].i1].pt.y};
    p2[i] = {(*kps2_)[matches_[i].i2].pt.x, (*kps2_)[matches_[i].i2].pt.y};
  }
  normalise(p1, n1, T1);
  normalise(p2, n2, T2);
}

TwoViewInitializer::TwoViewInitializer(const Camera& camera, const TwoViewOptions& options)
    : camera_(camera), options_(options) {
  K_ << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1;
}

Eigen::Matrix3d TwoViewInitializer::homographyDLT(const std::vector<Eigen::Vector2d>& p1,
                                                  const std::vector<Eigen::Vector2d>& p2) {
  const int n = static_cast<int>(p1.size());
  Eigen::MatrixXd A(2 * n, 9);
  for (int i = 0; i < n; ++i) {
    const double u1 = p1[i].x(), v1 = p1[i].y(), u2 = p2[i].x(), v2 = p2[i].y();
    A.row(2 * i) << 0, 0, 0, -u1, -v1, -1, v2 * u1, v2 * v1, v2;
    A.row(2 * i + 1) << u1, v1, 1, 0, 0, 0, -u2 * u1, -u2 * v1, -u2;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd h = svd.matrixV().col(8);
  Eigen::Matrix3d H;
  H << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  return H;
}

Eigen::Matrix3d TwoViewInitializer::fundamental8(const std::vector<Eigen::Vector2d>& p1,
                                                 const std::vector<Eigen::Vector2d>& p2) {
  const int n = static_cast<int>(p1.size());
  Eigen::MatrixXd A(n, 9);
  for (int i = 0; i < n; ++i) {
    const double u1 = p1[i].x(), v1 = p1[i].y(), u2 = p2[i].x(), v2 = p2[i].y();
    A.row(i) << u2 * u1, u2 * v1, u2, v2 * u1, v2 * v1, v2, u1, v1, 1;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd f = svd.matrixV().col(8);
  Eigen::Matrix3d F;
  F << f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7), f(8);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd2(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d s = svd2.singularValues();
  s(2) = 0;
  return svd2.matrixU() * s.asDiagonal() * svd2.matrixV().transpose();
}

Eigen::Vector3d TwoViewInitializer::triangulate(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2,
                                                const Eigen::Matrix<double, 3, 4>& P1,
                                                const Eigen::Matrix<double, 3, 4>& P2) {
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (std::abs(X(3)) < 1e-12) return Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  return X.head<3>() / X(3);
}

bool TwoViewInitializer::reconstruct(const std::vector<cv::KeyPoint>& kps1, const std::vector<cv::KeyPoint>& kps2,
                                     const std::vector<int>& matches12, TwoViewResult& result) {
  kps1_ = &kps1;
  kps2_ = &kps2;
  matches_.clear();
  for (size_t i = 0; i < matches12.size(); ++i)
    if (matches12[i] >= 0) matches_.push_back({static_cast<int>(i), matches12[i]});
  const int n = static_cast<int>(matches_.size());
  if (n < 8) return false;

  // The same random 8-point sets for both models.
  std::mt19937_64 rng(options_.seed);
  sets_.assign(options_.iterations, std::vector<int>(8));
  std::vector<int> all(n);
  for (auto& set : sets_) {
    std::iota(all.begin(), all.end(), 0);
    for (int j = 0; j < 8; ++j) {
      const int k = j + static_cast<int>(rng() % static_cast<uint64_t>(n - j));
      std::swap(all[j], all[k]);
      set[j] = all[j];
    }
  }

  std::vector<bool> inliers_h, inliers_f;
  double score_h = 0, score_f = 0;
  Eigen::Matrix3d H, F;
  auto h_job = std::async(std::launch::async, [&] { findHomography(inliers_h, score_h, H); });
  findFundamental(inliers_f, score_f, F);
  h_job.get();
  result.score_h = score_h;
  result.score_f = score_f;
  const double rh = score_h / std::max(score_h + score_f, 1e-12);
  result.points.assign(kps1.size(), Eigen::Vector3d::Zero());
  result.triangulated.assign(kps1.size(), false);
  if (rh > options_.homography_ratio) {
    result.used_homography = true;
    return reconstructH(inliers_h, H, result);
  }
  result.used_homography = false;
  return reconstructF(inliers_f, F, result);
}

template <typename Fit>
void TwoViewInitializer::bestOverSets(const std::vector<Eigen::Vector2d>& n1, const std::vector<Eigen::Vector2d>& n2,
                                      Fit fit, std::vector<bool>& inliers, double& score,
                                      Eigen::Matrix3d& model) const {
  score = 0;
  inliers.assign(matches_.size(), false);
  std::vector<Eigen::Vector2d> s1(8), s2(8);
  std::vector<bool> cur;
  Eigen::Matrix3d candidate;
  for (const auto& set : sets_) {
    for (int j = 0; j < 8; ++j) {
      s1[j] = n1[set[j]];
      s2[j] = n2[set[j]];
    }
    const double s = fit(s1, s2, cur, candidate);
    if (s > score) {
      score = s;
      inliers = cur;
      model = candidate;
    }
  }
}

void TwoViewInitializer::findHomography(std::vector<bool>& inliers, double& score, Eigen::Matrix3d& H21) const {
  std::vector<Eigen::Vector2d> n1, n2;
  Eigen::Matrix3d T1, T2;
  normaliseMatches(n1, T1, n2, T2);
  const Eigen::Matrix3d T2inv = T2.inverse();
  auto fit = [&](const std::vector<Eigen::Vector2d>& s1, const std::vector<Eigen::Vector2d>& s2, std::vector<bool>& cur,
                 Eigen::Matrix3d& h21) {
    h21 = T2inv * homographyDLT(s1, s2) * T1;
    if (std::abs(h21.determinant()) < 1e-15) return -1.0;  // degenerate sample: never the best
    return checkHomography(h21, h21.inverse(), cur);
  };
  bestOverSets(n1, n2, fit, inliers, score, H21);
}

void TwoViewInitializer::findFundamental(std::vector<bool>& inliers, double& score, Eigen::Matrix3d& F21) const {
  std::vector<Eigen::Vector2d> n1, n2;
  Eigen::Matrix3d T1, T2;
  normaliseMatches(n1, T1, n2, T2);
  auto fit = [&](const std::vector<Eigen::Vector2d>& s1, const std::vector<Eigen::Vector2d>& s2, std::vector<bool>& cur,
                 Eigen::Matrix3d& f21) {
    f21 = T2.transpose() * fundamental8(s1, s2) * T1;
    return checkFundamental(f21, cur);
  };
  bestOverSets(n1, n2, fit, inliers, score, F21);
}

template <class Check>
double TwoViewInitializer::scoreMatches(std::vector<bool>& inliers, Check check) const {
  inliers.assign(matches_.size(), false);
  double score = 0;
  for (size_t i = 0; i < matches_.size(); ++i) {
    const Eigen::Vector3d x1((*kps1_)[matches_[i].i1].pt.x, (*kps1_)[matches_[i].i1].pt.y, 1);
    const Eigen::Vector3d x2((*kps2_)[matches_[i].i2].pt.x, (*kps2_)[matches_[i].i2].pt.y, 1);
    inliers[i] = check(x1, x2, score);
  }
  return score;
}

double TwoViewInitializer::checkHomography(const Eigen::Matrix3d& H21, const Eigen::Matrix3d& H12,
                                           std::vector<bool>& inliers) const {
  const double th = 5.991, inv_s2 = 1.0 / (options_.sigma * options_.sigma);
  return scoreMatches(inliers, [&](const Eigen::Vector3d& x1, const Eigen::Vector3d& x2, double& score) {
    bool in = true;
    const Eigen::Vector3d x1p = H12 * x2;  // transfer 2 -> 1
    const double e1 = (x1.head<2>() - x1p.head<2>() / x1p.z()).squaredNorm() * inv_s2;
    if (e1 > th)
      in = false;
    else
      score += th - e1;
    const Eigen::Vector3d x2p = H21 * x1;
    const double e2 = (x2.head<2>() - x2p.head<2>() / x2p.z()).squaredNorm() * inv_s2;
    if (e2 > th)
      in = false;
    else
      score += th - e2;
    return in;
  });
}

double TwoViewInitializer::checkFundamental(const Eigen::Matrix3d& F21, std::vector<bool>& inliers) const {
  const double th = 3.841, th_score = 5.991, inv_s2 = 1.0 / (options_.sigma * options_.sigma);
  return scoreMatches(inliers, [&](const Eigen::Vector3d& x1, const Eigen::Vector3d& x2, double& score) {
    // x's squared distance to the epipolar line l, in sigma units: within th it adds to the score.
    const auto near = [&](const Eigen::Vector3d& l, const Eigen::Vector3d& x) {
      const double d = l.dot(x);
      const double e = d * d / (l.x() * l.x() + l.y() * l.y()) * inv_s2;
      if (e > th) return false;
      score += th_score - e;
      return true;
    };
    const bool in2 = near(F21 * x1, x2);              // line in image 2
    const bool in1 = near(F21.transpose() * x2, x1);  // line in image 1
    return in2 && in1;
  });
}

int TwoViewInitializer::checkRT(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const std::vector<bool>& inliers,
                                double th2, std::vector<Eigen::Vector3d>& points, std::vector<bool>& good,
                                double& parallax_deg) const {
  Eigen::Matrix<double, 3, 4> P1, P2;
  P1.setZero();
  P1.leftCols<3>() = K_;
  P2.leftCols<3>() = K_ * R;
  P2.col(3) = K_ * t;
  const Eigen::Vector3d O2 = -R.transpose() * t;
  points.assign(kps1_->size(), Eigen::Vector3d::Zero());
  good.assign(kps1_->size(), false);
  std::vector<double> cos_parallax;
  int n_good = 0;
  for (size_t i = 0; i < matches_.size(); ++i) {
    if (!inliers[i]) continue;
    const cv::KeyPoint& k1 = (*kps1_)[matches_[i].i1];
    const cv::KeyPoint& k2 = (*kps2_)[matches_[i].i2];
    const Eigen::Vector2d x1(k1.pt.x, k1.pt.y), x2(k2.pt.x, k2.pt.y);
    const Eigen::Vector3d X = triangulate(x1, x2, P1, P2);
    if (!X.allFinite()) continue;
    const Eigen::Vector3d n1 = X, n2 = X - O2;
    const double cosp = n1.dot(n2) / (n1.norm() * n2.norm());
    if (X.z() <= 0 && cosp < 0.99998) continue;
    const Eigen::Vector3d X2 = R * X + t;
    if (X2.z() <= 0 && cosp < 0.99998) continue;
    const Eigen::Vector3d u1 = K_ * X, u2 = K_ * X2;
    if ((u1.head<2>() / u1.z() - x1).squaredNorm() > th2) continue;
    if ((u2.head<2>() / u2.z() - x2).squaredNorm() > th2) continue;
    cos_parallax.push_back(cosp);
    points[matches_[i].i1] = X;
    ++n_good;
    if (cosp < 0.99998) good[matches_[i].i1] = true;
  }
  parallax_deg = 0;
  if (n_good > 0) {
    std::sort(cos_parallax.begin(), cos_parallax.end());  // descending parallax = ascending cosine
    // The 50th largest parallax (or the smallest when fewer): a robust lower bound.
    const size_t idx = std::min<size_t>(50, cos_parallax.size() - 1);
    parallax_deg = std::acos(std::clamp(cos_parallax[idx], -1.0, 1.0)) * 180.0 / M_PI;
  }
  return n_good;
}

bool TwoViewInitializer::reconstructF(const std::vector<bool>& inliers, const Eigen::Matrix3d& F21,
                                      TwoViewResult& r) const {
  const int n_inliers = static_cast<int>(std::count(inliers.begin(), inliers.end(), true));
  const Eigen::Matrix3d E = K_.transpose() * F21 * K_;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  Eigen::Matrix3d W;
  W << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  Eigen::Matrix3d R1 = U * W * V.transpose(), R2 = U * W.transpose() * V.transpose();
  if (R1.determinant() < 0) R1 = -R1;
  if (R2.determinant() < 0) R2 = -R2;
  const Eigen::Vector3d t = U.col(2).normalized();
  const Eigen::Matrix3d Rs[4] = {R1, R2, R1, R2};
  const Eigen::Vector3d ts[4] = {t, t, -t, -t};
  const double th2 = 4.0 * options_.sigma * options_.sigma;
  std::vector<Eigen::Vector3d> pts[4];
  std::vector<bool> good[4];
  double parallax[4];
  int n_good[4];
  for (int k = 0; k < 4; ++k) n_good[k] = checkRT(Rs[k], ts[k], inliers, th2, pts[k], good[k], parallax[k]);
  const int max_good = *std::max_element(n_good, n_good + 4);
  const int min_good = std::max(static_cast<int>(0.9 * n_inliers), options_.min_triangulated);
  int similar = 0;
  for (int k = 0; k < 4; ++k)
    if (n_good[k] > 0.7 * max_good) ++similar;
  if (max_good < min_good || similar > 1) return false;
  const int best = static_cast<int>(std::max_element(n_good, n_good + 4) - n_good);
  if (parallax[best] < options_.min_parallax_deg) return false;
  r.R21 = Rs[best];
  r.t21 = ts[best];
  r.points = pts[best];
  r.triangulated = good[best];
  r.n_triangulated = static_cast<int>(std::count(good[best].begin(), good[best].end(), true));
  return true;
}

bool TwoViewInitializer::reconstructH(const std::vector<bool>& inliers, const Eigen::Matrix3d& H21,
                                      TwoViewResult& r) const {
  const int n_inliers = static_cast<int>(std::count(inliers.begin(), inliers.end(), true));
  cv::Mat Hcv, Kcv;
  cv::eigen2cv(H21, Hcv);
  cv::eigen2cv(K_, Kcv);
  std::vector<cv::Mat> rotations, translations, normals;
  const int n_sol = cv::decomposeHomographyMat(Hcv, Kcv, rotations, translations, normals);
  const double th2 = 4.0 * options_.sigma * options_.sigma;
  int best_good = 0, second_good = 0, best = -1;
  double best_parallax = 0;
  std::vector<Eigen::Vector3d> best_pts;
  std::vector<bool> best_tri;
  Eigen::Matrix3d best_R;
  Eigen::Vector3d best_t;
  for (int k = 0; k < n_sol; ++k) {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    cv::cv2eigen(rotations[k], R);
    cv::cv2eigen(translations[k], t);
    if (t.norm() < 1e-12) continue;
    std::vector<Eigen::Vector3d> pts;
    std::vector<bool> good;
    double parallax = 0;
    const int n_good = checkRT(R, t, inliers, th2, pts, good, parallax);
    if (n_good > best_good) {
      second_good = best_good;
      best_good = n_good;
      best = k;
      best_parallax = parallax;
      best_pts = std::move(pts);
      best_tri = std::move(good);
      best_R = R;
      best_t = t;
    } else if (n_good > second_good) {
      second_good = n_good;
    }
  }
  if (best < 0) return false;
  if (second_good >= 0.75 * best_good || best_parallax < options_.min_parallax_deg ||
      best_good < options_.min_triangulated || best_good < 0.9 * n_inliers)
    return false;
  r.R21 = best_R;
  r.t21 = best_t;
  r.points = std::move(best_pts);
  r.triangulated = std::move(best_tri);
  r.n_triangulated = static_cast<int>(std::count(r.triangulated.begin(), r.triangulated.end(), true));
  return true;
}

}  // namespace beslam::orb
