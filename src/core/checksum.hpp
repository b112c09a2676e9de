#pragma once
// FNV-1a (64 bit) over a byte range: the checksum of the project's own binary files (vocabulary,
// occupancy-grid state). It catches truncation and flipped bytes; it is not cryptographic.
#include <cstddef>
#include <cstdint>

namespace builtscene {

inline std::uint64_t fnv1a64(const char* data, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace builtscene
