// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/mesh_topology.h"

#include <algorithm>
#include <cstdint>
#include <numeric>

namespace pointsurf {
namespace {

// One directed half-edge of a triangle, keyed by its undirected edge (lo, hi).
struct HalfEdge {
  int lo, hi;
  int from;       // start vertex of this half-edge (lo or hi): gives its direction
  int triangle;
  bool operator<(const HalfEdge& o) const noexcept { return lo != o.lo ? lo < o.lo : hi != o.hi ? hi < o.hi : triangle < o.triangle; }
};

struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

}  // namespace

MeshTopology analyze_topology(const TriangleMesh& mesh) {
  MeshTopology topo;
  const std::size_t nv = mesh.vertices.size();
  std::vector<HalfEdge> half_edges;
  half_edges.reserve(3 * mesh.triangles.size());
  std::vector<std::uint8_t> used(nv, 0);
  std::vector<int> kept;  // indices of non-degenerate triangles
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      ++topo.degenerate_triangles;
      continue;
    }
    kept.push_back(static_cast<int>(t));
    for (int c = 0; c < 3; ++c) {
      const int a = tri[c], b = tri[(c + 1) % 3];
      used[a] = 1;
      half_edges.push_back({std::min(a, b), std::max(a, b), a, static_cast<int>(t)});
    }
  }
  topo.triangles = kept.size();
  for (std::uint8_t u : used) topo.vertices += u;
  topo.isolated_vertices = nv - topo.vertices;
  std::sort(half_edges.begin(), half_edges.end());

  DisjointSets triangle_sets(mesh.triangles.size());
  // Boundary half-edges as directed edges from -> to, for the loop walk.
  std::vector<std::pair<int, int>> boundary;
  // Per vertex: number of incident boundary edges and of non-manifold edges.
  std::vector<int> boundary_degree(nv, 0);
  for (std::size_t i = 0; i < half_edges.size();) {
    std::size_t j = i + 1;
    while (j < half_edges.size() && half_edges[j].lo == half_edges[i].lo && half_edges[j].hi == half_edges[i].hi) ++j;
    const std::size_t count = j - i;
    ++topo.edges;
    if (count == 1) {
      ++topo.boundary_edges;
      const HalfEdge& h = half_edges[i];
      const int to = h.from == h.lo ? h.hi : h.lo;
      boundary.emplace_back(h.from, to);
      ++boundary_degree[h.lo];
      ++boundary_degree[h.hi];
    } else if (count == 2) {
      if (half_edges[i].from == half_edges[i + 1].from) ++topo.inconsistent_edges;
    } else {
      ++topo.non_manifold_edges;
    }
    for (std::size_t k = i + 1; k < j; ++k) triangle_sets.unite(half_edges[i].triangle, half_edges[k].triangle);
    i = j;
  }
  topo.euler_characteristic = static_cast<long>(topo.vertices) - static_cast<long>(topo.edges) + static_cast<long>(topo.triangles);
  for (int t : kept) topo.components += triangle_sets.find(t) == t;

  // Vertex manifoldness: the triangles around a vertex must form one fan (connected through
  // edges at that vertex). Count fans per vertex with union-find over the incident triangles.
  {
    std::vector<std::size_t> offsets(nv + 1, 0);
    for (int t : kept)
      for (int c = 0; c < 3; ++c) ++offsets[mesh.triangles[t][c] + 1];
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
    std::vector<int> incident(offsets.back());
    std::vector<std::size_t> fill(offsets.begin(), offsets.end() - 1);
    for (int t : kept)
      for (int c = 0; c < 3; ++c) incident[fill[mesh.triangles[t][c]]++] = t;
    std::vector<int> local_parent;
    std::vector<std::pair<int, int>> spokes;  // (other vertex, local triangle index)
    for (std::size_t v = 0; v < nv; ++v) {
      const std::size_t begin = offsets[v], n = offsets[v + 1] - begin;
      if (n == 0) continue;
      local_parent.resize(n);
      std::iota(local_parent.begin(), local_parent.end(), 0);
      auto find = [&](int x) {
        while (local_parent[x] != x) x = local_parent[x] = local_parent[local_parent[x]];
        return x;
      };
      spokes.clear();
      for (std::size_t i = 0; i < n; ++i) {
        const Triangle& tri = mesh.triangles[incident[begin + i]];
        for (int c = 0; c < 3; ++c)
          if (tri[c] != static_cast<int>(v)) spokes.emplace_back(tri[c], static_cast<int>(i));
      }
      std::sort(spokes.begin(), spokes.end());
      for (std::size_t i = 1; i < spokes.size(); ++i)
        if (spokes[i].first == spokes[i - 1].first) local_parent[find(spokes[i].second)] = find(spokes[i - 1].second);
      std::size_t fans = 0;
      for (std::size_t i = 0; i < n; ++i) fans += find(static_cast<int>(i)) == static_cast<int>(i);
      if (fans > 1 || boundary_degree[v] > 2) ++topo.non_manifold_vertices;
    }
  }

  // Boundary loops: follow directed boundary edges; only where every boundary vertex has
  // exactly one outgoing boundary edge is the walk unambiguous.
  {
    std::sort(boundary.begin(), boundary.end());
    std::vector<std::uint8_t> visited(boundary.size(), 0);
    auto next_of = [&](int from) -> std::ptrdiff_t {
      auto it = std::lower_bound(boundary.begin(), boundary.end(), std::make_pair(from, -1));
      if (it == boundary.end() || it->first != from) return -1;
      if (std::next(it) != boundary.end() && std::next(it)->first == from) return -1;  // ambiguous
      return it - boundary.begin();
    };
    for (std::size_t start = 0; start < boundary.size(); ++start) {
      if (visited[start]) continue;
      BoundaryLoop loop;
      std::ptrdiff_t e = static_cast<std::ptrdiff_t>(start);
      bool closed = false;
      while (e >= 0 && !visited[e]) {
        visited[e] = 1;
        loop.vertices.push_back(boundary[e].first);
        loop.length += (mesh.vertices[boundary[e].second] - mesh.vertices[boundary[e].first]).norm();
        if (boundary[e].second == loop.vertices.front()) {
          closed = true;
          break;
        }
        e = next_of(boundary[e].second);
      }
      if (closed) topo.boundary_loops.push_back(std::move(loop));
    }
    std::sort(topo.boundary_loops.begin(), topo.boundary_loops.end(),
              [](const BoundaryLoop& a, const BoundaryLoop& b) { return a.length > b.length; });
  }
  return topo;
}

}  // namespace pointsurf
