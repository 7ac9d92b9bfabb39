#include "beslam/formats/trajectory.hpp"

#include <charconv>
#include <cmath>
#include <ostream>
#include <sstream>
#include <string_view>

#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"

namespace beslam::formats {
namespace {

constexpr double kMaxRotationDefect = 1e-3;  // |R^T R - I| allowed in a KITTI row (printing precision)

bool isSeparator(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; }

// Calls row(numbers, line_number) for every data row (not blank, not a '#' comment) of the file,
// until row returns false.
template <typename RowFn>
void forEachRow(const std::string& path, const std::string& text, RowFn&& row) {
  std::vector<double> numbers;
  std::size_t begin = 0;
  int line_number = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string_view line(text.data() + begin, end - begin);
    begin = end + 1;
    ++line_number;

    std::size_t pos = 0;
    while (pos < line.size() && isSeparator(line[pos])) ++pos;
    if (pos == line.size() || line[pos] == '#') continue;

    numbers.clear();
    while (pos < line.size()) {
      std::size_t token_end = pos;
      while (token_end < line.size() && !isSeparator(line[token_end])) ++token_end;
      std::string_view token = line.substr(pos, token_end - pos);
      const std::string shown(token);
      if (!token.empty() && token.front() == '+') token.remove_prefix(1);
      double value = 0.0;
      const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
      if (token.empty() || ec == std::errc::invalid_argument || ptr != token.data() + token.size()) {
        throwAt(path, "column " + std::to_string(numbers.size() + 1) + ": '" + shown + "' is not a number",
                line_number);
      }
      if (ec == std::errc::result_out_of_range || !std::isfinite(value)) {
        throwAt(path, "column " + std::to_string(numbers.size() + 1) + ": non-finite value '" + shown + "'",
                line_number);
      }
      numbers.push_back(value);
      pos = token_end;
      while (pos < line.size() && isSeparator(line[pos])) ++pos;
    }
    if (!row(numbers, line_number)) return;
  }
}

void requireColumns(const std::string& path, const std::vector<double>& numbers, std::size_t expected,
                    const char* format, int line_number) {
  if (numbers.size() != expected) {
    throwAt(path,
            "expected " + std::to_string(expected) + " numbers per row (" + format + "), found " +
                std::to_string(numbers.size()),
            line_number);
  }
}

void requireNotEmpty(const std::string& path, const Trajectory& trajectory) {
  if (trajectory.empty()) throwAt(path, "no poses in file (empty or only comments)");
}

// Shortest decimal text that parses back to exactly `value`.
void putNumber(std::ostream& out, double value) {
  char buffer[64];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  (void)ec;  // 64 bytes always suffice for a double
  out.write(buffer, ptr - buffer);
}

}  // namespace

Trajectory readKitti(const std::string& path) {
  const std::string text = readFile(path);
  Trajectory trajectory;
  forEachRow(path, text, [&](const std::vector<double>& v, int line_number) {
    requireColumns(path, v, 12, "KITTI format", line_number);
    Eigen::Matrix4d T_world_cam = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) T_world_cam(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    }
    const Eigen::Matrix3d R = T_world_cam.topLeftCorner<3, 3>();
    const double defect = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (defect > kMaxRotationDefect || R.determinant() <= 0.0) {
      throwAt(path,
              "the 3x3 part is not a rotation matrix (max |R^T R - I| = " + std::to_string(defect) +
                  ", det = " + std::to_string(R.determinant()) + ")",
              line_number);
    }
    Eigen::Isometry3d pose;
    pose.matrix() = T_world_cam;  // kept as written, like evo
    trajectory.push_back(static_cast<double>(trajectory.size()), pose);
    return true;
  });
  requireNotEmpty(path, trajectory);
  return trajectory;
}

Trajectory readTum(const std::string& path) {
  const std::string text = readFile(path);
  Trajectory trajectory;
  forEachRow(path, text, [&](const std::vector<double>& v, int line_number) {
    requireColumns(path, v, 8, "TUM format: t x y z qx qy qz qw", line_number);
    Eigen::Quaterniond q_world_cam(v[7], v[4], v[5], v[6]);  // (w, x, y, z)
    const double norm = q_world_cam.norm();
    if (!(norm > 1e-9)) throwAt(path, "quaternion has zero length", line_number);
    q_world_cam.coeffs() /= norm;
    Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
    T_world_cam.linear() = q_world_cam.toRotationMatrix();
    T_world_cam.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    trajectory.push_back(v[0], T_world_cam);
    return true;
  });
  requireNotEmpty(path, trajectory);
  return trajectory;
}

std::string kittiRow(const Eigen::Isometry3d& T_world_cam) {
  std::ostringstream out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      if (r != 0 || c != 0) out << ' ';
      putNumber(out, T_world_cam.matrix()(r, c));
    }
  }
  out << '\n';
  return out.str();
}

std::string tumRow(double stamp, const Eigen::Isometry3d& T_world_cam) {
  Eigen::Quaterniond q_world_cam(T_world_cam.linear());
  q_world_cam.normalize();
  if (q_world_cam.w() < 0.0) q_world_cam.coeffs() *= -1.0;  // one canonical sign
  const Eigen::Vector3d t = T_world_cam.translation();
  const double values[8] = {stamp,           t.x(),           t.y(),           t.z(),
                            q_world_cam.x(), q_world_cam.y(), q_world_cam.z(), q_world_cam.w()};
  std::ostringstream out;
  for (int k = 0; k < 8; ++k) {
    if (k != 0) out << ' ';
    putNumber(out, values[k]);
  }
  out << '\n';
  return out.str();
}

void writeKitti(const std::string& path, const Trajectory& trajectory) {
  writeFileAtomic(path, [&](std::ostream& out) {
    for (const Eigen::Isometry3d& T_world_cam : trajectory.poses) out << kittiRow(T_world_cam);
  });
}

void writeTum(const std::string& path, const Trajectory& trajectory) {
  if (trajectory.stamps.size() != trajectory.poses.size()) {
    throwAt(path, "cannot write: trajectory has " + std::to_string(trajectory.stamps.size()) + " stamps for " +
                      std::to_string(trajectory.poses.size()) + " poses");
  }
  writeFileAtomic(path, [&](std::ostream& out) {
    out << kTumHeader;
    for (std::size_t i = 0; i < trajectory.size(); ++i) out << tumRow(trajectory.stamps[i], trajectory.poses[i]);
  });
}

Trajectory read(const std::string& path, const std::string& format) {
  if (format == "kitti") return readKitti(path);
  if (format == "tum") return readTum(path);
  throwAt(path, "unknown trajectory format '" + format + "' (expected kitti or tum)");
}

std::string detectFormat(const std::string& path) {
  const std::string text = readFile(path);
  std::string format;
  forEachRow(path, text, [&](const std::vector<double>& v, int line_number) {
    if (v.size() == 12) {
      format = "kitti";
    } else if (v.size() == 8) {
      format = "tum";
    } else {
      throwAt(path,
              "cannot tell the format: " + std::to_string(v.size()) + " numbers per row (KITTI has 12, TUM has 8)",
              line_number);
    }
    return false;  // the first data row decides
  });
  if (format.empty()) throwAt(path, "no poses in file (empty or only comments)");
  return format;
}

}  // namespace beslam::formats
