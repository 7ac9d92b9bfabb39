// Helpers for the fuzz targets: a per-process scratch file for readers that take a path, and the one
// answer a reader may give to bad input (beslam::Error).
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "beslam/formats/error.hpp"

namespace beslam::fuzz {

// Writes the input to a scratch file named `stem` (in the working folder, which run_fuzzer.sh makes a
// fresh temporary one) and returns its path.
inline std::string writeScratch(const uint8_t* data, size_t size, const std::string& stem) {
  const std::string path = stem + "." + std::to_string(::getpid());
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// Runs read(); a beslam::Error is the expected answer to bad input, anything else escapes to the fuzzer.
template <class Read>
void acceptErrors(Read&& read) {
  try {
    read();
  } catch (const beslam::Error&) {
  }
}

// A property a reader promises for what it accepts (finite numbers, increasing times, ...): a quiet wrong
// answer is a finding like a crash, so a broken promise aborts with `what` for libFuzzer to report.
inline void require(bool holds, const char* what) {
  if (!holds) {
    std::fprintf(stderr, "fuzz: broken promise: %s\n", what);
    std::abort();
  }
}

// For LLVMFuzzerInitialize: with BESLAM_FUZZ_WRITE_SEEDS set, the target writes its own seed inputs into that
// folder (write(dir)) and the process ends; otherwise 0, and fuzzing goes on.
template <class Write>
int writeSeedsIfAsked(Write&& write) {
  if (const char* dir = std::getenv("BESLAM_FUZZ_WRITE_SEEDS")) {
    write(dir);
    std::exit(0);
  }
  return 0;
}

// Writes `value` as 8 little-endian bytes at `at` of `bytes` (a file's size or checksum field made to fit).
inline void putLittleEndian64(std::string& bytes, size_t at, uint64_t value) {
  for (int i = 0; i < 8; ++i) bytes[at + static_cast<size_t>(i)] = static_cast<char>((value >> (8 * i)) & 0xff);
}

}  // namespace beslam::fuzz
