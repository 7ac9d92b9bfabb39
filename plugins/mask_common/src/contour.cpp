#include "beslam/mask_common/contour.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace beslam::mask {

namespace {

// The joint fit (step 4) over the six cubics' 24 coefficients: cost = 1/2 sum rho(r^2) over three kinds of
// term, minimised by Levenberg-Marquardt on the robustly reweighted normal equations (24 x 24, dense). A
// hand-written solver: Ceres' per-problem set-up cost ten times the solve itself at this size.
struct PointTerm {  // weight * Cauchy(2 px) of the vertical distance of an outline point to its piece's curve
  int piece;
  double t, y, weight;
};
struct JoinTerm {  // C0 join of two neighbouring curves at a shared x, squared, weighted inside r
  int a, b;
  double ta, tb, weight;
};
// Equation (3): the angle between the image gradient at an edge point (unit normal nx, ny) and the normal
// of the fitted curve at that x, as sin(angle) (edge polarity does not matter). With d = f'(x) the curve
// normal is (-d, 1) / n, n = sqrt(1 + d^2), and r = w (nx / n + ny d / n), dr/dd = w (ny - nx d) / n^3.
struct SmoothTerm {
  int piece;
  double t, half_width, nx, ny;
};
using Coefficients = std::array<std::array<double, 4>, 6>;
using Normal = Eigen::Matrix<double, 24, 24>;
using Vector24 = Eigen::Matrix<double, 24, 1>;

class CurveFit {
 public:
  CurveFit(double smooth_weight) : smooth_weight_(smooth_weight), smooth_b2_(sq(0.1 * smooth_weight)) {}
  std::vector<PointTerm> points;
  std::vector<JoinTerm> joins;
  std::vector<SmoothTerm> smooth;

  // 1/2 sum rho(r^2); with H and g also the reweighted Gauss-Newton system (sum rho' J^T J, sum rho' J^T r).
  double evaluate(const Coefficients& c, Normal* H, Vector24* g) const {
    if (H) H->setZero(), g->setZero();
    double cost = 0;
    auto add = [&](int piece, const double(&J)[4], double r, double w) {
      const int o = 4 * piece;
      for (int i = 0; i < 4; ++i) {
        (*g)(o + i) += w * J[i] * r;
        for (int k = 0; k < 4; ++k) (*H)(o + i, o + k) += w * J[i] * J[k];
      }
    };
    for (const PointTerm& p : points) {
      const double r = cubic(c[p.piece], p.t) - p.y, s = r * r;
      cost += 0.5 * p.weight * kCauchy2 * std::log1p(s / kCauchy2);
      if (H) add(p.piece, {1, p.t, p.t * p.t, p.t * p.t * p.t}, r, p.weight / (1 + s / kCauchy2));
    }
    for (const JoinTerm& j : joins) {
      const double r = j.weight * (cubic(c[j.a], j.ta) - cubic(c[j.b], j.tb));
      cost += 0.5 * r * r;
      if (!H) continue;
      const double Ja[4] = {j.weight, j.weight * j.ta, j.weight * j.ta * j.ta, j.weight * j.ta * j.ta * j.ta};
      const double Jb[4] = {-j.weight, -j.weight * j.tb, -j.weight * j.tb * j.tb, -j.weight * j.tb * j.tb * j.tb};
      add(j.a, Ja, r, 1.0);
      add(j.b, Jb, r, 1.0);
      for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 4; ++k) {
          (*H)(4 * j.a + i, 4 * j.b + k) += Ja[i] * Jb[k];
          (*H)(4 * j.b + k, 4 * j.a + i) += Ja[i] * Jb[k];
        }
    }
    for (const SmoothTerm& e : smooth) {
      const auto& a = c[e.piece];
      const double d = (a[1] + e.t * (2 * a[2] + 3 * e.t * a[3])) / e.half_width;
      const double n2 = 1 + d * d, n = std::sqrt(n2);
      const double r = smooth_weight_ * (e.nx + e.ny * d) / n, s = r * r;
      const double root = std::sqrt(1 + s / smooth_b2_);
      cost += smooth_b2_ * (root - 1);  // 1/2 of SoftLOne: 2 b^2 (sqrt(1 + s / b^2) - 1)
      if (!H) continue;
      const double drdd = smooth_weight_ * (e.ny - e.nx * d) / (n2 * n) / e.half_width;
      add(e.piece, {0, drdd, drdd * 2 * e.t, drdd * 3 * e.t * e.t}, r, 1 / root);
    }
    return cost;
  }

  // At most max_iterations trial steps; stops when a step lowers the cost by less than 1e-6 of it.
  void solve(Coefficients& c, int max_iterations) const {
    Normal H;
    Vector24 g;
    double cost = evaluate(c, &H, &g);
    double mu = 1e-4;  // damping, relative to the diagonal of H
    for (int it = 0; it < max_iterations; ++it) {
      Normal A = H;
      A.diagonal() += mu * H.diagonal().cwiseMax(1e-6);
      const Vector24 step = A.ldlt().solve(-g);
      if (!step.allFinite()) break;
      Coefficients trial = c;
      for (int p = 0; p < 6; ++p)
        for (int i = 0; i < 4; ++i) trial[p][i] += step(4 * p + i);
      const double trial_cost = evaluate(trial, nullptr, nullptr);
      if (!(trial_cost < cost)) {
        mu *= 4;
        continue;
      }
      const bool converged = cost - trial_cost < 1e-6 * cost;
      c = trial;
      cost = evaluate(c, &H, &g);
      mu = std::max(mu / 3, 1e-12);
      if (converged) break;
    }
  }

 private:
  static constexpr double kCauchy2 = 4.0;  // Cauchy scale 2 px, squared
  static double sq(double v) { return v * v; }
  static double cubic(const std::array<double, 4>& a, double t) { return a[0] + t * (a[1] + t * (a[2] + t * a[3])); }
  double smooth_weight_, smooth_b2_;
};

struct EdgePoint {
  int x, y;
  double nx, ny;  // unit image gradient
};

// Column extents of the region and of the fallback outline (-1 where a column is empty), and their
// horizontal and vertical spans.
struct ColumnExtents {
  std::vector<int> rTop, rBot, fTop, fBot;
  int xl = -1, xr = -1, y0 = 0, y1 = -1;  // the region's bounding rectangle (xl < 0: empty)
  int fl = -1, fr = -1;                   // the fallback's columns (fl < 0: empty)
};

// Column extents of the region and of the fallback outline.
ColumnExtents columnExtents(const cv::Mat& region, const cv::Mat& fallback) {
  const int W = region.cols, H = region.rows;
  ColumnExtents e;
  std::vector<int>&rTop = e.rTop, &rBot = e.rBot, &fTop = e.fTop, &fBot = e.fBot;
  rTop.assign(W, -1), rBot.assign(W, -1), fTop.assign(W, -1), fBot.assign(W, -1);
  for (int y = 0; y < H; ++y) {
    const uint8_t* r = region.ptr<uint8_t>(y);
    const uint8_t* f = fallback.ptr<uint8_t>(y);
    for (int x = 0; x < W; ++x) {
      if (r[x]) {
        if (rTop[x] < 0) rTop[x] = y;
        rBot[x] = y;
      }
      if (f[x]) {
        if (fTop[x] < 0) fTop[x] = y;
        fBot[x] = y;
      }
    }
  }
  e.y0 = H;
  for (int x = 0; x < W; ++x)
    if (rTop[x] >= 0) {
      if (e.xl < 0) e.xl = x;
      e.xr = x;
      e.y0 = std::min(e.y0, rTop[x]);
      e.y1 = std::max(e.y1, rBot[x]);
    }
  for (int x = 0; x < W; ++x)
    if (fTop[x] >= 0) {
      if (e.fl < 0) e.fl = x;
      e.fr = x;
    }
  return e;
}

// Unit Sobel gradient of the blurred crop at (x, y), clamped at the borders; false where it is flat.
bool gradientAt(const cv::Mat& blurred, int x, int y, double& nx, double& ny) {
  const int W = blurred.cols, H = blurred.rows;
  auto I = [&](int xx, int yy) {
    return static_cast<double>(blurred.at<uint8_t>(std::clamp(yy, 0, H - 1), std::clamp(xx, 0, W - 1)));
  };
  const double gx =
      (I(x + 1, y - 1) + 2 * I(x + 1, y) + I(x + 1, y + 1)) - (I(x - 1, y - 1) + 2 * I(x - 1, y) + I(x - 1, y + 1));
  const double gy =
      (I(x - 1, y + 1) + 2 * I(x, y + 1) + I(x + 1, y + 1)) - (I(x - 1, y - 1) + 2 * I(x, y - 1) + I(x + 1, y - 1));
  const double n = std::hypot(gx, gy);
  if (n < 1e-9) return false;
  nx = gx / n, ny = gy / n;
  return true;
}

// Six equal rectangles of the region's bounding rectangle, clockwise from the top left.
struct Piece {
  double xa, xb;
  bool top;
};
struct Pieces {
  double xb[4];  // column boundaries
  Piece piece[6];
  // The rectangle of column x in the top or the bottom row.
  int of(int x, bool top) const {
    const int col = x < xb[1] ? 0 : (x < xb[2] ? 1 : 2);
    return top ? col : 5 - col;
  }
};

Pieces sixPieces(int xl, int xr) {
  Pieces p{{static_cast<double>(xl), xl + (xr - xl) / 3.0, xl + 2 * (xr - xl) / 3.0, static_cast<double>(xr)}, {}};
  const double* xb = p.xb;
  const Piece pieces[6] = {{xb[0], xb[1], true},  {xb[1], xb[2], true},  {xb[2], xb[3], true},
                           {xb[2], xb[3], false}, {xb[1], xb[2], false}, {xb[0], xb[1], false}};
  std::copy(pieces, pieces + 6, p.piece);
  return p;
}

using PiecePoints = std::array<std::vector<EdgePoint>, 6>;

// Outline edge points per column (step 3): the outermost edge pixel of each column in each row of
// rectangles, or with a prior the edge pixel nearest the prior's outline.
PiecePoints outlineEdgePoints(const cv::Mat& edges, const cv::Mat& blurred, const ColumnExtents& ext, const Pieces& pc,
                              bool has_prior, const ContourParams& params) {
  const std::vector<int>&rTop = ext.rTop, &rBot = ext.rBot, &fTop = ext.fTop, &fBot = ext.fBot;
  const double ymid = 0.5 * (ext.y0 + ext.y1);
  PiecePoints pts;
  const int tol = static_cast<int>(std::lround(params.prior_tolerance_px));
  for (int x = ext.xl; x <= ext.xr; ++x) {
    if (rTop[x] < 0) continue;
    for (int side = 0; side < 2; ++side) {
      const bool top = side == 0;
      int found = -1;
      if (has_prior) {
        const int ref = top ? fTop[x] : fBot[x];
        if (ref < 0) continue;
        int best = tol + 1;
        for (int y = std::max(rTop[x], ref - tol); y <= std::min(rBot[x], ref + tol); ++y)
          if (edges.at<uint8_t>(y, x) && std::abs(y - ref) < best) best = std::abs(y - ref), found = y;
      } else if (top) {
        for (int y = rTop[x]; y <= std::min<int>(rBot[x], static_cast<int>(ymid)); ++y)
          if (edges.at<uint8_t>(y, x)) {
            found = y;
            break;
          }
      } else {
        for (int y = rBot[x]; y >= std::max<int>(rTop[x], static_cast<int>(std::ceil(ymid))); --y)
          if (edges.at<uint8_t>(y, x)) {
            found = y;
            break;
          }
      }
      if (found < 0) continue;
      EdgePoint e{x, found, 0, 0};
      if (!gradientAt(blurred, x, found, e.nx, e.ny)) continue;
      pts[pc.of(x, top)].push_back(e);
    }
  }
  return pts;
}

using PieceData = std::array<std::vector<cv::Point2d>, 6>;

// Data of each rectangle: its edge points, or the fallback outline where edges are weak (whose edge
// points are then dropped); and the initial least-squares cubic of each rectangle into result.curves.
PieceData initialCurves(const ColumnExtents& ext, const Pieces& pc, PiecePoints& pts, ContourResult& result) {
  const Piece* pieces = pc.piece;
  PieceData data;
  for (int i = 0; i < 6; ++i) {
    if (result.from_edges[i]) {
      for (const EdgePoint& e : pts[i]) data[i].emplace_back(e.x, e.y);
    } else {
      for (int x = static_cast<int>(std::ceil(pieces[i].xa)); x <= pieces[i].xb && x <= ext.xr; ++x) {
        const int y = pieces[i].top ? ext.fTop[x] : ext.fBot[x];
        if (y >= 0) data[i].emplace_back(x, y);
      }
      pts[i].clear();
    }
    Cubic& c = result.curves[i];
    c.x_mid = 0.5 * (pieces[i].xa + pieces[i].xb);
    c.half_width = std::max(1.0, 0.5 * (pieces[i].xb - pieces[i].xa));
    // Initial least-squares cubic (degree reduced when there are few points).
    const int n = static_cast<int>(data[i].size());
    const double y_default = pieces[i].top ? ext.y0 : ext.y1;
    if (n == 0) {
      c.c = {y_default, 0, 0, 0};
      continue;
    }
    const int deg = std::min(3, n - 1);
    cv::Mat A(n, deg + 1, CV_64F), b(n, 1, CV_64F), sol;
    for (int k = 0; k < n; ++k) {
      const double t = (data[i][k].x - c.x_mid) / c.half_width;
      double p = 1;
      for (int j = 0; j <= deg; ++j) A.at<double>(k, j) = p, p *= t;
      b.at<double>(k) = data[i][k].y;
    }
    cv::solve(A, b, sol, cv::DECOMP_SVD);
    c.c = {0, 0, 0, 0};
    for (int j = 0; j <= deg; ++j) c.c[j] = sol.at<double>(j);
  }
  return data;
}

// Neighbours sharing an end: R1-R2, R2-R3 (top row) and R4-R5, R5-R6 (bottom row) at the column
// boundaries. (R3-R4 and R6-R1 meet through the region's vertical sides.)
constexpr int kJoins[4][2] = {{0, 1}, {1, 2}, {3, 4}, {4, 5}};

// Joint refinement (CurveFit above) of result.curves.
void refineJointly(const Pieces& pc, const PiecePoints& pts, const PieceData& data, const ContourParams& params,
                   ContourResult& result) {
  const Piece* pieces = pc.piece;
  CurveFit fit(params.smooth_weight);
  for (int i = 0; i < 6; ++i) {
    const Cubic& c = result.curves[i];
    // Evenly thinned to at most max_points_per_piece (the fit is over-determined long before that).
    const size_t stride =
        std::max<size_t>(1, (data[i].size() + params.max_points_per_piece - 1) / params.max_points_per_piece);
    const double weight = (result.from_edges[i] ? 1.0 : 0.5) * static_cast<double>(stride);
    for (size_t k = 0; k < data[i].size(); k += stride)
      fit.points.push_back({i, (data[i][k].x - c.x_mid) / c.half_width, data[i][k].y, weight});
  }
  for (const auto& j : kJoins) {
    const Cubic& a = result.curves[j[0]];
    const Cubic& b = result.curves[j[1]];
    const double x = (j[0] < 3) ? pieces[j[0]].xb : pieces[j[0]].xa;  // shared boundary
    fit.joins.push_back({j[0], j[1], (x - a.x_mid) / a.half_width, (x - b.x_mid) / b.half_width, params.join_weight});
    // Equation (3): the M edge points of both rectangles near the shared boundary, against both curves.
    const double band = std::max(2.0, 0.25 * (pieces[j[0]].xb - pieces[j[0]].xa));
    for (int side = 0; side < 2; ++side) {
      const size_t stride = std::max<size_t>(1, pts[j[side]].size() / params.max_points_per_piece);
      for (size_t q = 0; q < pts[j[side]].size(); q += stride) {
        const EdgePoint& e = pts[j[side]][q];
        if (std::abs(e.x - x) > band) continue;
        for (int k = 0; k < 2; ++k) {
          const Cubic& c = result.curves[j[k]];
          fit.smooth.push_back({j[k], (e.x - c.x_mid) / c.half_width, c.half_width, e.nx, e.ny});
        }
      }
    }
  }
  Coefficients coef;
  for (int i = 0; i < 6; ++i) coef[i] = result.curves[i].c;
  fit.solve(coef, params.max_iterations);
  for (int i = 0; i < 6; ++i) result.curves[i].c = coef[i];
}

// Equation (3) at the solution, for reporting: mean |sin| of the angle over the M edge points.
double smoothnessAt(const Pieces& pc, const PiecePoints& pts, const ContourResult& result) {
  const Piece* pieces = pc.piece;
  double xi = 0;
  int m = 0;
  for (const auto& j : kJoins) {
    const double x = (j[0] < 3) ? pieces[j[0]].xb : pieces[j[0]].xa;
    const double band = std::max(2.0, 0.25 * (pieces[j[0]].xb - pieces[j[0]].xa));
    for (int side = 0; side < 2; ++side)
      for (const EdgePoint& e : pts[j[side]]) {
        if (std::abs(e.x - x) > band) continue;
        const double d = result.curves[j[side]].slope(e.x);
        const double n = std::hypot(d, 1.0);
        xi += std::abs(e.nx * (1 / n) - e.ny * (-d / n));
        ++m;
      }
  }
  return m ? xi / m : 0;
}

// The closed contour: top curve left to right, bottom curve right to left, within the region's and
// (with a prior) the prior's horizontal extent, filled into result.mask and clipped to the region; false
// (result untouched) when fewer than three columns remain.
bool fillContour(const cv::Mat& region, const ColumnExtents& ext, const Pieces& pc, bool has_prior,
                 ContourResult& result) {
  const int xa = !has_prior ? ext.xl : std::max(ext.xl, ext.fl), xz = !has_prior ? ext.xr : std::min(ext.xr, ext.fr);
  std::vector<cv::Point> top, bottom;
  for (int x = xa; x <= xz; ++x) {
    if (ext.rTop[x] < 0) continue;
    double yt = result.curves[pc.of(x, true)](x);
    double yb = result.curves[pc.of(x, false)](x);
    yt = std::clamp(yt, static_cast<double>(ext.rTop[x]), static_cast<double>(ext.rBot[x]));
    yb = std::clamp(yb, static_cast<double>(ext.rTop[x]), static_cast<double>(ext.rBot[x]));
    if (yb < yt) continue;
    top.emplace_back(x, static_cast<int>(std::lround(yt)));
    bottom.emplace_back(x, static_cast<int>(std::lround(yb)));
  }
  if (top.size() < 3) return false;
  std::vector<cv::Point> contour(top.begin(), top.end());
  contour.insert(contour.end(), bottom.rbegin(), bottom.rend());
  cv::Mat filled = cv::Mat::zeros(region.size(), CV_8UC1);
  cv::fillPoly(filled, std::vector<std::vector<cv::Point>>{contour}, cv::Scalar(255));
  cv::bitwise_and(filled, region, result.mask);
  return true;
}

}  // namespace

ContourResult refineContour(const cv::Mat& gray_crop, const cv::Mat& region, const cv::Mat& prior,
                            const ContourParams& params) {
  CV_Assert(gray_crop.type() == CV_8UC1 && region.type() == CV_8UC1 && gray_crop.size() == region.size());
  CV_Assert(prior.empty() || (prior.type() == CV_8UC1 && prior.size() == region.size()));
  ContourResult result;
  const cv::Mat fallback = prior.empty() ? region : prior;
  result.mask = fallback.clone();
  const int W = region.cols, H = region.rows;
  if (W < params.min_size_px || H < params.min_size_px) return result;

  const ColumnExtents ext = columnExtents(region, fallback);
  if (ext.xl < 0 || ext.xr - ext.xl + 1 < params.min_size_px || ext.y1 - ext.y0 + 1 < params.min_size_px) return result;
  if (ext.fl < 0) return result;

  cv::Mat blurred, edges;
  cv::GaussianBlur(gray_crop, blurred, cv::Size(3, 3), 0);
  cv::Canny(blurred, edges, params.canny_low, params.canny_high, 3, true);
  const Pieces pc = sixPieces(ext.xl, ext.xr);
  PiecePoints pts = outlineEdgePoints(edges, blurred, ext, pc, !prior.empty(), params);

  // Support and fallback per rectangle.
  int total_cols = 0, total_pts = 0;
  std::array<int, 6> cols{};
  for (int i = 0; i < 6; ++i) {
    for (int x = static_cast<int>(std::ceil(pc.piece[i].xa)); x <= pc.piece[i].xb && x <= ext.xr; ++x)
      if (ext.rTop[x] >= 0 && pc.of(x, pc.piece[i].top) == i) ++cols[i];
    total_cols += cols[i];
    total_pts += static_cast<int>(pts[i].size());
    result.from_edges[i] = cols[i] > 0 && pts[i].size() >= params.min_support * cols[i] && pts[i].size() >= 4;
  }
  result.support = total_cols ? static_cast<double>(total_pts) / total_cols : 0;
  if (result.support < params.min_total_support) return result;

  const PieceData data = initialCurves(ext, pc, pts, result);
  refineJointly(pc, pts, data, params, result);
  result.smoothness = smoothnessAt(pc, pts, result);
  if (!fillContour(region, ext, pc, !prior.empty(), result)) return result;
  result.refined = true;
  return result;
}

}  // namespace beslam::mask
