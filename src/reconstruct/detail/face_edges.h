// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The undirected edges of a mesh's faces, sorted so that the faces sharing an edge are
// adjacent: what flat regions and component clean-up walk across.
#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf::detail {

struct FaceEdge {
  int lo, hi;  // vertex indices, lo < hi
  int face;
  bool operator<(const FaceEdge& o) const noexcept { return lo != o.lo ? lo < o.lo : hi != o.hi ? hi < o.hi : face < o.face; }
  bool same_edge(const FaceEdge& o) const noexcept { return lo == o.lo && hi == o.hi; }
};

/// Every edge of every face (3F records, an edge with a repeated vertex left out), sorted by
/// edge then face. Parallel.
inline std::vector<FaceEdge> sorted_face_edges(const TriangleMesh& mesh) {
  const std::size_t f = mesh.triangles.size();
  std::vector<FaceEdge> edges(3 * f, FaceEdge{-1, -1, -1});
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t)
      for (int c = 0; c < 3; ++c) {
        const int a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3];
        if (a != b) edges[3 * t + std::size_t(c)] = FaceEdge{std::min(a, b), std::max(a, b), static_cast<int>(t)};
      }
  });
  edges.erase(std::remove_if(edges.begin(), edges.end(), [](const FaceEdge& e) { return e.face < 0; }), edges.end());
  tbb::parallel_sort(edges.begin(), edges.end());
  return edges;
}

/// Calls visit(begin, end) for each run of records of one edge in `edges` (sorted).
template <typename Visit>
void for_each_edge(const std::vector<FaceEdge>& edges, Visit&& visit) {
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j].same_edge(edges[i])) ++j;
    visit(i, j);
    i = j;
  }
}

/// Union-find over face indices with path halving.
struct FaceSets {
  std::vector<int> parent;
  explicit FaceSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[std::size_t(x)] != x) x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
    return x;
  }
  void unite(int a, int b) { parent[std::size_t(find(a))] = find(b); }
};

}  // namespace pointsurf::detail
