// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/mesh_topology.h"

#include <algorithm>
#include <cstdint>
#include <numeric>

namespace pointsurf {
namespace {

struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

// One triangle around a vertex v, seen from v: the other vertex w of one of its two edges at v,
// whether that edge runs v -> w in the triangle (else w -> v), and the triangle's index in v's list.
struct Spoke {
  int w;
  bool outgoing;
  int local;
  bool operator<(const Spoke& o) const noexcept { return w != o.w ? w < o.w : local < o.local; }
};

}  // namespace

// Linear in the mesh size: every edge is seen from the triangle lists of its two vertices
// (counting sort by vertex), where the spokes of one vertex are few; no global sort.
MeshTopology analyze_topology(const TriangleMesh& mesh) {
  MeshTopology topo;
  const std::size_t nv = mesh.vertices.positions.size();
  std::vector<int> kept;  // indices of non-degenerate triangles
  kept.reserve(mesh.triangles.size());
  std::vector<std::size_t> offsets(nv + 1, 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      ++topo.degenerate_triangles;
      continue;
    }
    kept.push_back(static_cast<int>(t));
    for (int c = 0; c < 3; ++c) ++offsets[std::size_t(tri[c]) + 1];
  }
  topo.triangles = kept.size();
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<int> incident(offsets.back());
  {
    std::vector<std::size_t> fill(offsets.begin(), offsets.end() - 1);
    for (int t : kept)
      for (int c = 0; c < 3; ++c) incident[fill[std::size_t(mesh.triangles[t][c])]++] = t;
  }

  DisjointSets triangle_sets(mesh.triangles.size());
  // Boundary edges from -> to, filed by `from` (out_offsets after the pass below).
  std::vector<std::pair<int, int>> boundary;
  std::vector<int> local_parent;
  std::vector<Spoke> spokes;
  for (std::size_t v = 0; v < nv; ++v) {
    const std::size_t begin = offsets[v], n = offsets[v + 1] - begin;
    if (n == 0) continue;
    ++topo.vertices;
    local_parent.resize(n);
    std::iota(local_parent.begin(), local_parent.end(), 0);
    auto find = [&](int x) {
      while (local_parent[x] != x) x = local_parent[x] = local_parent[local_parent[x]];
      return x;
    };
    spokes.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const Triangle& tri = mesh.triangles[incident[begin + i]];
      const int c = tri[0] == int(v) ? 0 : tri[1] == int(v) ? 1 : 2;
      spokes.push_back({tri[(c + 1) % 3], true, int(i)});
      spokes.push_back({tri[(c + 2) % 3], false, int(i)});
    }
    std::sort(spokes.begin(), spokes.end());
    int boundary_degree = 0;
    for (std::size_t i = 0; i < spokes.size();) {
      std::size_t j = i + 1;
      while (j < spokes.size() && spokes[j].w == spokes[i].w) ++j;
      const std::size_t count = j - i;
      const int w = spokes[i].w;
      for (std::size_t k = i + 1; k < j; ++k) local_parent[find(spokes[k].local)] = find(spokes[i].local);
      if (count == 1) ++boundary_degree;
      // Each undirected edge is counted at its smaller vertex.
      if (int(v) < w) {
        ++topo.edges;
        if (count == 1) {
          ++topo.boundary_edges;
          if (spokes[i].outgoing) boundary.emplace_back(int(v), w);
          else boundary.emplace_back(w, int(v));
        } else if (count == 2) {
          if (spokes[i].outgoing == spokes[i + 1].outgoing) ++topo.inconsistent_edges;
        } else {
          ++topo.non_manifold_edges;
        }
        for (std::size_t k = i + 1; k < j; ++k) triangle_sets.unite(incident[begin + std::size_t(spokes[i].local)], incident[begin + std::size_t(spokes[k].local)]);
      }
      i = j;
    }
    // The triangles around a vertex must form one fan (connected through edges at that vertex).
    std::size_t fans = 0;
    for (std::size_t i = 0; i < n; ++i) fans += find(static_cast<int>(i)) == static_cast<int>(i);
    if (fans > 1 || boundary_degree > 2) ++topo.non_manifold_vertices;
  }
  topo.isolated_vertices = nv - topo.vertices;
  topo.euler_characteristic = static_cast<long>(topo.vertices) - static_cast<long>(topo.edges) + static_cast<long>(topo.triangles);
  for (int t : kept) topo.components += triangle_sets.find(t) == t;

  // Boundary loops: follow directed boundary edges; only where every boundary vertex has
  // exactly one outgoing boundary edge is the walk unambiguous. Edges by (from, to) through a
  // counting sort by `from`.
  {
    std::vector<std::size_t> out_offsets(nv + 1, 0);
    for (const auto& e : boundary) ++out_offsets[std::size_t(e.first) + 1];
    std::partial_sum(out_offsets.begin(), out_offsets.end(), out_offsets.begin());
    std::vector<std::pair<int, int>> sorted(boundary.size());
    {
      std::vector<std::size_t> fill(out_offsets.begin(), out_offsets.end() - 1);
      for (const auto& e : boundary) sorted[fill[std::size_t(e.first)]++] = e;
    }
    for (std::size_t v = 0; v < nv; ++v)
      if (out_offsets[v + 1] - out_offsets[v] > 1)
        std::sort(sorted.begin() + std::ptrdiff_t(out_offsets[v]), sorted.begin() + std::ptrdiff_t(out_offsets[v + 1]));
    std::vector<std::uint8_t> visited(sorted.size(), 0);
    auto next_of = [&](int from) -> std::ptrdiff_t {
      const std::size_t f = std::size_t(from);
      return out_offsets[f + 1] - out_offsets[f] == 1 ? std::ptrdiff_t(out_offsets[f]) : -1;  // none, or ambiguous
    };
    for (std::size_t start = 0; start < sorted.size(); ++start) {
      if (visited[start]) continue;
      BoundaryLoop loop;
      std::ptrdiff_t e = static_cast<std::ptrdiff_t>(start);
      bool closed = false;
      while (e >= 0 && !visited[e]) {
        visited[e] = 1;
        loop.vertices.push_back(sorted[e].first);
        loop.length += (mesh.vertices.positions[sorted[e].second] - mesh.vertices.positions[sorted[e].first]).norm();
        if (sorted[e].second == loop.vertices.front()) {
          closed = true;
          break;
        }
        e = next_of(sorted[e].second);
      }
      if (closed) topo.boundary_loops.push_back(std::move(loop));
    }
    std::sort(topo.boundary_loops.begin(), topo.boundary_loops.end(),
              [](const BoundaryLoop& a, const BoundaryLoop& b) { return a.length > b.length; });
  }
  return topo;
}

}  // namespace pointsurf
