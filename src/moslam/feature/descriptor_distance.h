// Hamming distance of 256-bit ORB descriptors (Rublee et al. 2011), by 64-bit popcount.
#pragma once

#include <cstdint>
#include <cstring>

namespace moslam::feature {

// Bits that differ between two 32-byte descriptors, in [0, 256].
inline int DescriptorDistance(const uint8_t* a, const uint8_t* b) {
  int distance = 0;
  for (int i = 0; i < 32; i += 8) {
    uint64_t x, y;
    std::memcpy(&x, a + i, 8);  // memcpy: descriptor rows need not be 8-byte aligned
    std::memcpy(&y, b + i, 8);
    distance += __builtin_popcountll(x ^ y);
  }
  return distance;
}

}  // namespace moslam::feature
