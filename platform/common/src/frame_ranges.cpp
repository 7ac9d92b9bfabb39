// Parsing of frame numbers and ranges ("520-539,600").
#include "beslam/common/frame_ranges.hpp"

#include <algorithm>
#include <cctype>

#include "beslam/common/error.hpp"

namespace beslam {
namespace {

std::string rangeText(const FrameRange& r) {
  return r.first == r.last ? std::to_string(r.first) : std::to_string(r.first) + "-" + std::to_string(r.last);
}

// A frame number: digits only (no sign, no spaces inside), at most 12 of them.
std::int64_t frameNumberOf(const std::string& text, const std::string& item) {
  if (text.empty() || text.size() > 12 ||
      !std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
    throw Error("'" + item + "' is not a frame number or a range FIRST-LAST of frame numbers");
  return std::stoll(text);
}

std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

}  // namespace

std::vector<FrameRange> parseFrameRanges(const std::string& text) {
  std::vector<FrameRange> ranges;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string item =
        trimmed(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (item.empty()) throw Error("empty entry in '" + text + "' (expected e.g. \"520-539\" or \"520-539,600\")");
    const std::size_t dash = item.find('-');
    FrameRange r;
    if (dash == std::string::npos) {
      r.first = r.last = frameNumberOf(item, item);
    } else {
      r.first = frameNumberOf(trimmed(item.substr(0, dash)), item);
      r.last = frameNumberOf(trimmed(item.substr(dash + 1)), item);
      if (r.last < r.first) throw Error("range " + item + " ends before it starts");
    }
    if (!ranges.empty() && r.first <= ranges.back().last)
      throw Error("range " + rangeText(r) + " does not come after " + rangeText(ranges.back()) +
                  " (ranges must be ascending and must not overlap)");
    ranges.push_back(r);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return ranges;
}

std::string frameRangesText(const std::vector<FrameRange>& ranges) {
  std::string text;
  for (const FrameRange& r : ranges) text += (text.empty() ? "" : ",") + rangeText(r);
  return text;
}

}  // namespace beslam
