#include "beslam/detector_replay/replay.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "beslam/formats/labels.hpp"

namespace beslam::detector_replay {

namespace {

constexpr int64_t kMaxFrame = 10'000'000;
constexpr size_t kMaxProblems = 20;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

[[noreturn]] void failAt(const std::string& path, int line_no, const std::string& message) {
  throw std::runtime_error(path + ":" + std::to_string(line_no) + ": " + message);
}

bool parseNumber(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

// Comma-separated when the line has a comma (fields trimmed, empty fields kept), else whitespace-separated.
std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> out;
  auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  if (line.find(',') != std::string_view::npos) {
    size_t start = 0;
    while (true) {
      const size_t end = std::min(line.find(',', start), line.size());
      std::string_view f = line.substr(start, end - start);
      while (!f.empty() && space(f.front())) f.remove_prefix(1);
      while (!f.empty() && space(f.back())) f.remove_suffix(1);
      out.push_back(f);
      if (end >= line.size()) break;
      start = end + 1;
    }
    return out;
  }
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && space(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !space(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

bool dataLine(const std::string& line) {
  const auto first = line.find_first_not_of(" \t\r");
  return first != std::string::npos && line[first] != '#';
}

float transformScore(double raw, ScoreTransform t) {
  if (t == ScoreTransform::sigmoid) return static_cast<float>(1.0 / (1.0 + std::exp(-raw)));
  return static_cast<float>(raw);
}

void checkGeometry(const beslam_box3d& b, const std::string& path, int line_no) {
  for (int k = 0; k < 3; ++k)
    if (!(b.size[k] > 0)) failAt(path, line_no, "non-positive box size (h w l must be > 0)");
}

// Runs `parse` for every data line of `path`; applies the policy to its exceptions.
template <class F>
void forEachRow(const std::string& path, Policy policy, Report& report, F&& parse) {
  forEachLine(path, "detections file", [&](const std::string& line, int line_no) {
    if (!dataLine(line)) return;
    ++report.rows;
    try {
      parse(line, line_no);
    } catch (const std::exception& e) {
      if (policy == Policy::stop) throw std::runtime_error(e.what());
      ++report.skipped;
      report.problem(e.what());
    }
  });
}

void keep(const beslam_box3d& box, int64_t frame, const Filter& filter, DetectionTable& table, Report& report) {
  table.cover(frame);
  if (!filter.keeps(box)) {
    ++report.filtered;
    return;
  }
  table.add(frame, box);
  ++report.boxes;
}

beslam_box3d boxFromLabel(const formats::ObjectLabel& o, int32_t class_id, ScoreTransform transform,
                          const std::string& path, int line_no) {
  beslam_box3d b =
      boxFromKitti(class_id, o.h, o.w, o.l, o.p_cam_bottom.x(), o.p_cam_bottom.y(), o.p_cam_bottom.z(), o.ry);
  checkGeometry(b, path, line_no);
  b.bbox2d[0] = o.x1, b.bbox2d[1] = o.y1, b.bbox2d[2] = o.x2, b.bbox2d[3] = o.y2;
  b.flags |= BESLAM_BOX_HAS_BBOX2D;
  b.score = o.score ? transformScore(*o.score, transform) : 1.0f;
  b.truncation = static_cast<float>(std::clamp(o.truncated, 0.0, 1.0));
  b.occlusion = o.occluded;
  return b;
}

}  // namespace

void Report::problem(const std::string& message) {
  if (problems.size() < kMaxProblems) problems.push_back(message);
}

bool Filter::keeps(const beslam_box3d& b) const {
  if (!classes.empty() && std::find(classes.begin(), classes.end(), b.class_id) == classes.end()) return false;
  if (static_cast<double>(b.score) < min_score) return false;
  if (b.center_cam[2] < min_depth) return false;
  const double d = std::sqrt(b.center_cam[0] * b.center_cam[0] + b.center_cam[1] * b.center_cam[1] +
                             b.center_cam[2] * b.center_cam[2]);
  return d <= max_distance;
}

void DetectionTable::cover(int64_t frame) {
  if (frame < 0 || frame > kMaxFrame) throw std::out_of_range("frame index out of range");
  if (static_cast<size_t>(frame) >= frames_.size()) frames_.resize(static_cast<size_t>(frame) + 1);
}

void DetectionTable::add(int64_t frame, const beslam_box3d& box) {
  cover(frame);
  frames_[static_cast<size_t>(frame)].push_back(box);
}

const std::vector<beslam_box3d>& DetectionTable::at(int64_t frame) const {
  static const std::vector<beslam_box3d> kEmpty;
  if (frame < 0 || frame >= static_cast<int64_t>(frames_.size())) return kEmpty;
  return frames_[static_cast<size_t>(frame)];
}

int64_t DetectionTable::boxCount() const {
  int64_t n = 0;
  for (const auto& f : frames_) n += static_cast<int64_t>(f.size());
  return n;
}

bool ab3dmotClass(int64_t id, int32_t& class_id) {
  switch (id) {
    case 1:
      class_id = BESLAM_CLASS_PEDESTRIAN;
      return true;
    case 2:
      class_id = BESLAM_CLASS_CAR;
      return true;
    case 3:
      class_id = BESLAM_CLASS_CYCLIST;
      return true;
    default:
      return false;
  }
}

bool nuscenesClass(const std::string& name, int32_t& class_id) {
  static const formats::NamedClass kNuscenes[] = {{"car", BESLAM_CLASS_CAR},
                                                  {"truck", BESLAM_CLASS_TRUCK},
                                                  {"bus", BESLAM_CLASS_TRUCK},
                                                  {"trailer", BESLAM_CLASS_TRUCK},
                                                  {"construction_vehicle", BESLAM_CLASS_TRUCK},
                                                  {"pedestrian", BESLAM_CLASS_PEDESTRIAN},
                                                  {"bicycle", BESLAM_CLASS_CYCLIST},
                                                  {"motorcycle", BESLAM_CLASS_CYCLIST},
                                                  {"barrier", BESLAM_CLASS_UNKNOWN},
                                                  {"traffic_cone", BESLAM_CLASS_UNKNOWN}};
  return formats::classByName(name, kNuscenes, class_id);
}

std::vector<int32_t> parseClassList(const std::string& list) {
  std::vector<int32_t> out;
  std::stringstream ss(list);
  for (std::string item; std::getline(ss, item, ',');) {
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    const std::string l = lower(item);
    if (l.empty()) continue;
    if (l == "all") return {};
    if (l == "car")
      out.push_back(BESLAM_CLASS_CAR);
    else if (l == "van")
      out.push_back(BESLAM_CLASS_VAN);
    else if (l == "truck")
      out.push_back(BESLAM_CLASS_TRUCK);
    else if (l == "pedestrian")
      out.push_back(BESLAM_CLASS_PEDESTRIAN);
    else if (l == "cyclist")
      out.push_back(BESLAM_CLASS_CYCLIST);
    else if (l == "unknown" || l == "misc")
      out.push_back(BESLAM_CLASS_UNKNOWN);
    else
      throw std::invalid_argument("unknown class '" + item +
                                  "' (known: Car, Van, Truck, Pedestrian, Cyclist, Unknown, or all)");
  }
  return out;
}

beslam_box3d parseAb3dmotRow(const std::string& line, const std::string& path, int line_no, ScoreTransform transform,
                             int64_t& frame) {
  static const char* const kNames[] = {"frame", "class id", "x1", "y1", "x2", "y2", "score", "h",
                                       "w",     "l",        "x",  "y",  "z",  "ry", "alpha"};
  const std::vector<std::string_view> f = splitFields(line);
  if (f.size() != 15)
    failAt(path, line_no,
           "expected 15 fields (frame, class id, x1 y1 x2 y2, score, h w l, x y z, ry, alpha), got " +
               std::to_string(f.size()));
  double v[15];
  for (int i = 0; i < 15; ++i) {
    if (!parseNumber(f[i], v[i]))
      failAt(path, line_no, std::string(kNames[i]) + " '" + std::string(f[i]) + "' is not a number");
    if (!std::isfinite(v[i]))
      failAt(path, line_no, std::string(kNames[i]) + " is not finite ('" + std::string(f[i]) + "')");
  }
  if (v[0] != std::floor(v[0]) || v[0] < 0 || v[0] > kMaxFrame)
    failAt(path, line_no, "frame '" + std::string(f[0]) + "' is not a frame index");
  // Class ids are small integers; anything outside int32 cannot be one (and would overflow the cast).
  if (v[1] != std::floor(v[1]) || std::fabs(v[1]) > 2147483647.0)
    failAt(path, line_no, "class id '" + std::string(f[1]) + "' is not an integer class id");
  int32_t class_id = 0;
  if (!ab3dmotClass(static_cast<int64_t>(v[1]), class_id))
    failAt(path, line_no, "unknown class id " + std::string(f[1]) + " (known: 1 Pedestrian, 2 Car, 3 Cyclist)");
  frame = static_cast<int64_t>(v[0]);
  beslam_box3d b = boxFromKitti(class_id, v[7], v[8], v[9], v[10], v[11], v[12], v[13]);
  checkGeometry(b, path, line_no);
  b.bbox2d[0] = v[2], b.bbox2d[1] = v[3], b.bbox2d[2] = v[4], b.bbox2d[3] = v[5];
  b.flags |= BESLAM_BOX_HAS_BBOX2D;
  b.score = transformScore(v[6], transform);
  return b;
}

void readAb3dmotFile(const std::string& path, const Filter& filter, Policy policy, ScoreTransform transform,
                     DetectionTable& table, Report& report) {
  forEachRow(path, policy, report, [&](const std::string& line, int line_no) {
    int64_t frame = 0;
    const beslam_box3d b = parseAb3dmotRow(line, path, line_no, transform, frame);
    keep(b, frame, filter, table, report);
  });
}

void readKittiTrackingFile(const std::string& path, const Filter& filter, Policy policy, ScoreTransform transform,
                           DetectionTable& table, Report& report) {
  forEachRow(path, policy, report, [&](const std::string& line, int line_no) {
    const formats::TrackingLabel t = formats::parseTrackingRow(line, path, line_no);
    if (t.frame < 0 || t.frame > kMaxFrame)
      failAt(path, line_no, "frame " + std::to_string(t.frame) + " is out of range");
    if (t.object.isDontCare()) {
      table.cover(t.frame);
      ++report.filtered;
      return;
    }
    int32_t class_id = 0;
    if (!kittiClass(t.object.type, class_id)) failAt(path, line_no, "unknown class '" + t.object.type + "'");
    beslam_box3d b = boxFromLabel(t.object, class_id, transform, path, line_no);
    keep(b, t.frame, filter, table, report);
  });
}

void readKittiObjectFile(const std::string& path, int64_t frame, const Filter& filter, Policy policy,
                         ScoreTransform transform, DetectionTable& table, Report& report) {
  table.cover(frame);
  forEachRow(path, policy, report, [&](const std::string& line, int line_no) {
    const formats::ObjectLabel o = formats::parseObjectRow(line, path, line_no);
    if (o.isDontCare()) {
      ++report.filtered;
      return;
    }
    int32_t class_id = 0;
    if (!kittiClass(o.type, class_id)) failAt(path, line_no, "unknown class '" + o.type + "'");
    keep(boxFromLabel(o, class_id, transform, path, line_no), frame, filter, table, report);
  });
}

void forEachLine(const std::string& path, const std::string& what,
                 const std::function<void(const std::string& line, int line_no)>& each) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open " + what);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    each(line, line_no);
  }
}

}  // namespace beslam::detector_replay
