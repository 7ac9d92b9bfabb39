// FNV-1a, 64 bit: the checksum of the shape prior file (the same function as backend_orb's vocabulary
// and map files; a copy, so this plugin does not depend on that one). Catches truncation and damage.
#pragma once

#include <cstddef>
#include <cstdint>

namespace beslam::recon::shape {

inline std::uint64_t fnv1a(const char* data, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<std::uint8_t>(data[i]);
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace beslam::recon::shape
