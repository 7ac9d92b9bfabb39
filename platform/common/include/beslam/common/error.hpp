// beslam::Error: the one exception type the host throws for bad input or failed I/O.
// Its message always names what failed and where ("FILE:LINE: cause" or "FILE: cause"), so the CLI
// prints it as the single error line a user sees. Exceptions never leave the host through the C ABI.
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
