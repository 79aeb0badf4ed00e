// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Disjoint sets over 0..n-1 with path halving and union by size.
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace pointsurf::detail {

class UnionFind {
public:
  explicit UnionFind(std::size_t n) : parent_(n), size_(n, 1) { std::iota(parent_.begin(), parent_.end(), std::uint32_t(0)); }
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a == b) return;
    if (size_[a] < size_[b]) std::swap(a, b);
    parent_[b] = a;
    size_[a] += size_[b];
  }

private:
  std::vector<std::uint32_t> parent_;
  std::vector<std::uint32_t> size_;
};

}  // namespace pointsurf::detail
