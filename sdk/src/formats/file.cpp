#include "beslam/formats/file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "beslam/formats/error.hpp"

namespace beslam {

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throwAt(path, std::string("cannot open file: ") + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throwAt(path, "read error");
  return buffer.str();
}

void writeFileAtomic(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throwAt(path, std::string("cannot write file: ") + std::strerror(errno));
      write(out);
      out.flush();
      if (!out) throwAt(path, "write failed (disk full?)");
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) throwAt(path, "cannot move temporary file into place: " + ec.message());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
}

void writeFileAtomic(const std::string& path, const std::string& content) {
  writeFileAtomic(path, [&](std::ostream& out) { out << content; });
}

}  // namespace beslam
