// Whole-file reads and atomic writes: writeFileAtomic writes to a temporary sibling and renames it over
// the target, so a crash or an error mid-write never leaves a truncated file where a good one was.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace beslam {

// Reads a whole file; throws beslam::Error naming the path if it is missing or unreadable.
std::string readFile(const std::string& path);

// Calls write(stream) on a temporary file beside `path`, then renames it to `path`.
// Throws beslam::Error (and removes the temporary) if the stream fails or write throws.
void writeFileAtomic(const std::string& path, const std::function<void(std::ostream&)>& write);

// Convenience: writeFileAtomic with a whole string.
void writeFileAtomic(const std::string& path, const std::string& content);

}  // namespace beslam
