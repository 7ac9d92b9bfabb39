#include "beslam/formats/labels.hpp"

#include <cmath>
#include <cstdio>

#include "beslam/formats/error.hpp"
#include "beslam/formats/file.hpp"
#include "beslam/formats/text.hpp"

namespace beslam::formats {
namespace {

const char* const kObjectFields[] = {"type", "truncated", "occluded", "alpha", "x1", "y1", "x2", "y2",
                                     "h",    "w",         "l",        "x",     "y",  "z",  "ry", "score"};

double number(const std::vector<std::string_view>& tokens, std::size_t i, const char* field, const std::string& path,
              int line_no) {
  double v = 0;
  if (!parseDouble(tokens[i], v))
    throwAt(path, std::string(field) + " '" + std::string(tokens[i]) + "' is not a number", line_no);
  return v;
}

std::int64_t integer(const std::vector<std::string_view>& tokens, std::size_t i, const char* field,
                     const std::string& path, int line_no) {
  std::int64_t v = 0;
  if (parseInt(tokens[i], v)) return v;
  // Some writers print integral fields as floats ("0.00", "-1.000000").
  double d = 0;
  if (parseDouble(tokens[i], d) && d == std::floor(d) && std::abs(d) < 9e15) return static_cast<std::int64_t>(d);
  throwAt(path, std::string(field) + " '" + std::string(tokens[i]) + "' is not an integer", line_no);
}

// Fields from `offset` on: type truncated occluded alpha bbox(4) hwl(3) xyz(3) ry [score].
ObjectLabel parseObjectFields(const std::vector<std::string_view>& tokens, std::size_t offset, const std::string& path,
                              int line_no) {
  ObjectLabel o;
  o.type = std::string(tokens[offset]);
  double probe = 0;
  if (parseDouble(o.type, probe)) throwAt(path, "type '" + o.type + "' is a number, expected a class name", line_no);
  std::size_t i = offset + 1;
  auto next = [&](std::size_t k) { return number(tokens, i++, kObjectFields[k], path, line_no); };
  o.truncated = next(1);
  o.occluded = static_cast<int>(integer(tokens, i++, "occluded", path, line_no));
  o.alpha = next(3);
  o.x1 = next(4);
  o.y1 = next(5);
  o.x2 = next(6);
  o.y2 = next(7);
  o.h = next(8);
  o.w = next(9);
  o.l = next(10);
  o.p_cam_bottom.x() = next(11);
  o.p_cam_bottom.y() = next(12);
  o.p_cam_bottom.z() = next(13);
  o.ry = next(14);
  if (i < tokens.size()) o.score = next(15);
  return o;
}

void appendNumber(std::string& out, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, " %.6f", v);
  out += buf;
}

void appendObjectFields(std::string& out, const ObjectLabel& o, bool integral_truncation) {
  out += o.type;
  if (integral_truncation && o.truncated == std::floor(o.truncated))
    out += " " + std::to_string(static_cast<long long>(o.truncated));
  else
    appendNumber(out, o.truncated);
  out += " " + std::to_string(o.occluded);
  for (double v : {o.alpha, o.x1, o.y1, o.x2, o.y2, o.h, o.w, o.l, o.p_cam_bottom.x(), o.p_cam_bottom.y(),
                   o.p_cam_bottom.z(), o.ry})
    appendNumber(out, v);
  if (o.score) appendNumber(out, *o.score);
}

template <typename Row, typename Parse>
std::vector<Row> readRows(const std::string& path, Parse parse) {
  const std::string text = readFile(path);
  std::vector<Row> rows;
  const auto lines = splitLines(text);
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (!isBlank(lines[i])) rows.push_back(parse(std::string(lines[i]), path, static_cast<int>(i + 1)));
  return rows;
}

}  // namespace

ObjectLabel parseObjectRow(const std::string& line, const std::string& path, int line_no) {
  const auto tokens = splitWhitespace(line);
  if (tokens.size() != 15 && tokens.size() != 16)
    throwAt(path, "object label row has " + std::to_string(tokens.size()) + " fields, expected 15 or 16", line_no);
  return parseObjectFields(tokens, 0, path, line_no);
}

TrackingLabel parseTrackingRow(const std::string& line, const std::string& path, int line_no) {
  const auto tokens = splitWhitespace(line);
  if (tokens.size() != 17 && tokens.size() != 18)
    throwAt(path, "tracking label row has " + std::to_string(tokens.size()) + " fields, expected 17 or 18", line_no);
  TrackingLabel t;
  t.frame = integer(tokens, 0, "frame", path, line_no);
  if (t.frame < 0) throwAt(path, "negative frame number", line_no);
  t.track_id = integer(tokens, 1, "track_id", path, line_no);
  t.object = parseObjectFields(tokens, 2, path, line_no);
  return t;
}

std::vector<ObjectLabel> readObjectLabels(const std::string& path) {
  return readRows<ObjectLabel>(path, parseObjectRow);
}

std::vector<TrackingLabel> readTrackingLabels(const std::string& path) {
  return readRows<TrackingLabel>(path, parseTrackingRow);
}

std::map<std::pair<std::int64_t, std::int64_t>, bool> readObjectMotion(const std::string& path) {
  const std::string text = readFile(path);
  const auto lines = splitLines(text);
  std::map<std::pair<std::int64_t, std::int64_t>, bool> moving;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto tokens = splitWhitespace(lines[i]);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    std::int64_t frame = 0, track = 0;
    double speed = 0;
    if (tokens.size() != 4 || !parseInt(tokens[0], frame) || !parseInt(tokens[1], track) ||
        (tokens[2] != "0" && tokens[2] != "1") || !parseDouble(tokens[3], speed) || !std::isfinite(speed))
      throwAt(path, "expected 'frame track_id moving(0/1) speed', got '" + std::string(lines[i]) + "'",
              static_cast<int>(i + 1));
    moving[{frame, track}] = tokens[2] == "1";
  }
  return moving;
}

std::string formatObjectRow(const ObjectLabel& label) {
  std::string out;
  appendObjectFields(out, label, false);
  return out;
}

std::string formatTrackingRow(const TrackingLabel& label) {
  std::string out = std::to_string(label.frame) + " " + std::to_string(label.track_id) + " ";
  appendObjectFields(out, label.object, true);
  return out;
}

}  // namespace beslam::formats
