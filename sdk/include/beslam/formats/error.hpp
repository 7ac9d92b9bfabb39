// beslam::Error: the one exception type for bad input or failed I/O, shared by the host and the SDK's
// formats. Its message always names what failed and where ("FILE:LINE: cause" or "FILE: cause").
// A plugin may throw it; the SDK turns it into a status at the C boundary like any other exception.
#pragma once

#include <stdexcept>
#include <string>

namespace beslam {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// "path: message", or "path:line: message" when line > 0.
[[noreturn]] void throwAt(const std::string& path, const std::string& message, int line = 0);

}  // namespace beslam
