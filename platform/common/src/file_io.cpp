#include "beslam/common/file_io.hpp"

#include <filesystem>

#include "beslam/common/error.hpp"

namespace beslam {

void makeDirectories(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec) throwAt(path, "cannot create directory: " + ec.message());
}

}  // namespace beslam
