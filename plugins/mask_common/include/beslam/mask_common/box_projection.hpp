// Box projection: a 3D box (camera frame, geometric centre, KITTI yaw) to its image polygon.
// The box solid is clipped at the near plane z = near before projecting, so a box that straddles the
// camera projects to the image of its visible part (not to a polygon folded through infinity); the
// projection of the clipped convex solid is the convex hull of its projected vertices.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "beslam/data.h"

namespace beslam::mask {

struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  Eigen::Vector2d project(const Eigen::Vector3d& p) const { return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy}; }
};
Intrinsics fromCamera(const beslam_camera& camera);

// Vertices of the box solid intersected with the half-space z >= near: the corners in front plus the
// points where the twelve edges cross the plane. Empty when the whole box is behind the plane.
std::vector<Eigen::Vector3d> clippedBoxVertices(const beslam_box3d& box, double near);

// Convex image polygon (pixel coordinates, pixel centres at integers) of the clipped box, grown by
// margin_px on every side (Minkowski sum with an octagon), then clipped to the image rectangle grown by
// `guard` pixels so coordinates stay small. Empty when nothing of the box is in front of the camera or
// the polygon misses the image.
std::vector<cv::Point2f> projectBoxPolygon(const beslam_box3d& box, const Intrinsics& K, double near, double margin_px,
                                           double guard = 16.0);

// Sutherland-Hodgman clip of a convex polygon against an axis-aligned rectangle.
std::vector<cv::Point2f> clipPolygonToRect(const std::vector<cv::Point2f>& polygon, const cv::Rect2f& rect);

// What to do with a box whose motion state is unknown (or static without a track id).
enum class UnknownPolicy { Dynamic, Static, Skip };
UnknownPolicy parseUnknownPolicy(const std::string& text);  // "dynamic" | "static" | "skip"

// The mask label of a box: BESLAM_LABEL_DYNAMIC for dynamic boxes, BESLAM_LABEL_STATIC_BASE + track_id
// for static boxes with a track id; unknown boxes by policy (Static needs a track id, else dynamic).
// nullopt: do not draw. Track ids beyond the 16-bit label range are drawn as dynamic (never dropped).
std::optional<uint16_t> labelFor(const beslam_box3d& box, UnknownPolicy unknown);

}  // namespace beslam::mask
