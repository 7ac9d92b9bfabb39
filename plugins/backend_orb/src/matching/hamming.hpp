// Hamming distance between two 256-bit descriptors.
#pragma once

#include <cstdint>
#include <cstring>

namespace beslam::orb {

inline int hamming(const uint8_t* a, const uint8_t* b) {
  int d = 0;
  for (int i = 0; i < 4; ++i) {
    uint64_t x, y;
    std::memcpy(&x, a + 8 * i, 8);
    std::memcpy(&y, b + 8 * i, 8);
    d += __builtin_popcountll(x ^ y);
  }
  return d;
}

}  // namespace beslam::orb
