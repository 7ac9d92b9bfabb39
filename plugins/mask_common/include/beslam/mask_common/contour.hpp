// Edge contour refinement (the paper's mask step after Algorithm 1, equation (3)), computed on the
// object's own crop:
//  1. Canny edges of the grey crop inside the projected region (the box polygon).
//  2. The region's bounding rectangle split into six equal rectangles (2 rows x 3 columns), numbered
//     clockwise from the top left: R1 R2 R3 on top, R4 R5 R6 at the bottom right to left.
//  3. In each rectangle the outline's edge points: per column, the outermost edge pixel (topmost in the
//     top row, lowest in the bottom row); with a prior mask (LiDAR points) the edge pixel nearest the
//     prior's outline. A cubic y = f_i(x) is fitted to each rectangle's points.
//  4. Levenberg-Marquardt minimises, jointly over the six cubics: robust point distances, C0 joins of neighbouring
//     curves at their shared ends, and equation (3), xi = sum_j |d_e - d_j| over the M edge points near
//     each shared boundary: the angle between the image gradient at the edge point (d_e) and the normal
//     of the fitted curve there (d_j), as |sin| so edge polarity does not matter.
//  5. The closed contour (top curve left to right, bottom curve back) is filled as the mask and clipped
//     to the region. A rectangle with too few edge points (weak edges) falls back to the region's own
//     outline there (the prior's if given, else the projected polygon's); with too few edges overall the
//     whole result is the fallback region.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <vector>

namespace beslam::mask {

struct ContourParams {
  double canny_low = 30, canny_high = 90;  // on the 3x3-blurred grey crop
  double min_support = 0.3;                // a rectangle needs edge points in this fraction of its columns
  double min_total_support = 0.3;          // over all six; below: the fallback region as is
  double smooth_weight = 3.0;              // weight of the equation (3) term against the point distances (px)
  double join_weight = 10.0;               // weight of the C0 joins (per px of gap)
  double prior_tolerance_px = 6;           // with a prior: edge points this close to the prior outline only
  int max_iterations = 10;
  int max_points_per_piece = 30;  // edge points per rectangle in the optimisation (evenly thinned)
  int min_size_px = 10;           // crops narrower or lower than this keep the fallback region
};

struct Cubic {
  double x_mid = 0, half_width = 1;  // t = (x - x_mid) / half_width in [-1, 1]
  std::array<double, 4> c{};         // y = c0 + c1 t + c2 t^2 + c3 t^3
  double operator()(double x) const {
    const double t = (x - x_mid) / half_width;
    return c[0] + t * (c[1] + t * (c[2] + t * c[3]));
  }
  double slope(double x) const {  // dy/dx
    const double t = (x - x_mid) / half_width;
    return (c[1] + t * (2 * c[2] + 3 * t * c[3])) / half_width;
  }
};

struct ContourResult {
  cv::Mat mask;                      // CV_8UC1 of the crop's size, 255 inside
  bool refined = false;              // false: the fallback region was returned
  std::array<Cubic, 6> curves{};     // R1..R6 in crop pixel coordinates
  std::array<bool, 6> from_edges{};  // rectangle fitted to edges (false: to the fallback outline)
  double support = 0;                // fraction of columns with edge points, all rectangles
  double smoothness = 0;             // equation (3) at the solution: mean |sin(d_e - d_j)| over the M points
};

// gray_crop: CV_8UC1 crop of the object (roi of the frame); region: CV_8UC1 same size, the projected
// polygon; prior: empty or CV_8UC1 same size (e.g. the LiDAR point mask), used to pick edge points and
// as the fallback outline.
ContourResult refineContour(const cv::Mat& gray_crop, const cv::Mat& region, const cv::Mat& prior,
                            const ContourParams& params);

}  // namespace beslam::mask
