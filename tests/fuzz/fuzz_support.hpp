// Helpers for the fuzz targets: a per-process scratch file for readers that take a path.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace beslam::fuzz {

// Writes the input to a scratch file named `stem` (in the working folder, which run_fuzzer.sh makes a
// fresh temporary one) and returns its path.
inline std::string writeScratch(const uint8_t* data, size_t size, const std::string& stem) {
  const std::string path = stem + "." + std::to_string(::getpid());
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

}  // namespace beslam::fuzz
