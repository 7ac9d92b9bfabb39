// Frame numbers and inclusive ranges of them as a user writes them in a pipeline: "520-539,600".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace beslam {

// Frame numbers first..last, inclusive.
struct FrameRange {
  std::int64_t first = 0, last = 0;
  bool contains(std::int64_t frame) const { return frame >= first && frame <= last; }
};

// "520-539", "7", "520-539,600-619": comma-separated frame numbers and inclusive ranges, ascending and not
// overlapping. Throws beslam::Error saying what is wrong (callers add the file and key).
std::vector<FrameRange> parseFrameRanges(const std::string& text);
std::string frameRangesText(const std::vector<FrameRange>& ranges);  // back to "520-539,600"

}  // namespace beslam
