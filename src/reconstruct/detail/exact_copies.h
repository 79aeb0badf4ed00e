// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Exact copies among the samples, found by sorting: a stack of m identical points (a scanner's
// "no return" points, merged overlapping scans) costs O(m log m) here instead of the O(m^2) of
// radius queries that each return the whole stack.
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <tbb/parallel_sort.h>

#include "core/detail/lexicographic.h"

namespace pointsurf::detail {

// 1 for every point with an identical point of lower index, 0 otherwise (the first of each
// stack is the one kept).
inline std::vector<std::uint8_t> later_exact_copies(std::span<const Eigen::Vector3d> positions) {
  std::vector<std::uint32_t> order(positions.size());
  std::iota(order.begin(), order.end(), std::uint32_t{0});
  tbb::parallel_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const Eigen::Vector3d &p = positions[a], &q = positions[b];
    return lexicographic_less(p, q) || (p == q && a < b);
  });
  std::vector<std::uint8_t> copy(positions.size(), 0);
  for (std::size_t q = 1; q < order.size(); ++q)
    if (positions[order[q]] == positions[order[q - 1]]) copy[order[q]] = 1;
  return copy;
}

}  // namespace pointsurf::detail
