#include "beslam/formats/error.hpp"

namespace beslam {

void throwAt(const std::string& path, const std::string& message, int line) {
  if (line > 0) throw Error(path + ":" + std::to_string(line) + ": " + message);
  throw Error(path + ": " + message);
}

}  // namespace beslam
