// FNV-1a, 64 bit: the checksum of backend_orb's binary files (vocabulary, map). Not cryptographic; it
// catches truncated and damaged files.
#pragma once

#include <cstddef>
#include <cstdint>

namespace beslam::orb {

inline uint64_t fnv1a(const char* data, size_t n) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= static_cast<uint8_t>(data[i]);
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace beslam::orb
