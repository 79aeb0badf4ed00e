// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Morton (Z-order) codes of integer cell coordinates, shared by the point ordering
// (spatial/morton_order.cpp), the Poisson octree and the primitive detector's cells.
#include <cstdint>

namespace pointsurf::detail {

/// Spreads the low 21 bits of v so that two zero bits separate each of them.
inline std::uint64_t morton_spread(std::uint64_t v) {
  v &= 0x1fffffULL;
  v = (v | (v << 32)) & 0x1f00000000ffffULL;
  v = (v | (v << 16)) & 0x1f0000ff0000ffULL;
  v = (v | (v << 8)) & 0x100f00f00f00f00fULL;
  v = (v | (v << 4)) & 0x10c30c30c30c30c3ULL;
  v = (v | (v << 2)) & 0x1249249249249249ULL;
  return v;
}

/// The 63-bit code of cell (x, y, z), each coordinate below 2^21: x in the lowest bit.
inline std::uint64_t morton_code(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  return morton_spread(x) | morton_spread(y) << 1 | morton_spread(z) << 2;
}

}  // namespace pointsurf::detail
