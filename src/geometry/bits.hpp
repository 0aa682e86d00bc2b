// Bit helpers of the branch-free code paths (geometry and mesh layers).
#pragma once

#include <cstdint>

namespace crux::detail {

/// Index of the lowest set bit of mask (mask != 0): the count of trailing zeros.
inline int lowestBit(std::uint64_t mask) {
#if defined(__GNUC__)
  return __builtin_ctzll(mask);
#else
  int i = 0;
  while (!(mask & 1u)) mask >>= 1, ++i;
  return i;
#endif
}

}  // namespace crux::detail
