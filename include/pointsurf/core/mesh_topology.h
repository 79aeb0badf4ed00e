// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Combinatorial structure of a triangle mesh: edges, boundary loops (holes), manifoldness,
// orientation consistency, connected components and the Euler characteristic. Every
// reconstruction reports it, and the tests check it.
#include <cstddef>
#include <vector>

#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

/// One closed chain of boundary edges (a hole, or the rim of an open surface).
struct BoundaryLoop {
  std::vector<int> vertices;  // vertex indices in order along the loop (first not repeated)
  double length = 0.0;        // perimeter, cloud units
};

struct MeshTopology {
  std::size_t vertices = 0;               // V: vertices used by at least one triangle
  std::size_t isolated_vertices = 0;      // vertices used by no triangle
  std::size_t triangles = 0;              // F: non-degenerate triangles
  std::size_t degenerate_triangles = 0;   // triangles with a repeated vertex index (ignored above)
  std::size_t edges = 0;                  // E: distinct undirected edges
  std::size_t boundary_edges = 0;         // edges with exactly one triangle
  std::size_t non_manifold_edges = 0;     // edges with three or more triangles (0 is better)
  std::size_t non_manifold_vertices = 0;  // vertices whose triangle fan is not one disc or half-disc
  std::size_t inconsistent_edges = 0;     // two-triangle edges traversed in the same direction by
                                          // both (0: consistently oriented)
  std::size_t components = 0;             // connected components (triangles sharing edges)
  long euler_characteristic = 0;          // V - E + F
  std::vector<BoundaryLoop> boundary_loops;  // only where the boundary is edge-manifold; longest first

  bool edge_manifold() const noexcept { return non_manifold_edges == 0; }
  bool closed() const noexcept { return boundary_edges == 0; }
  bool oriented() const noexcept { return inconsistent_edges == 0; }
  /// Closed, edge- and vertex-manifold, consistently oriented.
  bool watertight() const noexcept {
    return closed() && edge_manifold() && non_manifold_vertices == 0 && oriented() && triangles > 0;
  }
  /// Genus of the surface, the one definition of the project: for one connected, orientable
  /// (consistently oriented), edge-manifold component whose boundary edges all lie on the
  /// reported loops, (2 - chi - b) / 2 with b the number of boundary loops (a sphere or a disc
  /// 0, a torus 1); -1 otherwise (several components, non-manifold or inconsistent edges).
  long genus() const noexcept {
    if (triangles == 0 || components != 1 || !edge_manifold() || !oriented()) return -1;
    std::size_t loop_edges = 0;
    for (const BoundaryLoop& loop : boundary_loops) loop_edges += loop.vertices.size();
    if (loop_edges != boundary_edges) return -1;
    const long twice = 2 - euler_characteristic - static_cast<long>(boundary_loops.size());
    return twice >= 0 && twice % 2 == 0 ? twice / 2 : -1;
  }
  /// Handles summed over the components: (2 c - chi - b) / 2 with c components, under the
  /// conditions of genus() but for any number of components (Poisson's output with its small
  /// pieces); -1 otherwise. Equals genus() on one component.
  long handles() const noexcept {
    if (triangles == 0 || !edge_manifold() || !oriented()) return -1;
    std::size_t loop_edges = 0;
    for (const BoundaryLoop& loop : boundary_loops) loop_edges += loop.vertices.size();
    if (loop_edges != boundary_edges) return -1;
    const long twice = 2 * static_cast<long>(components) - euler_characteristic - static_cast<long>(boundary_loops.size());
    return twice >= 0 && twice % 2 == 0 ? twice / 2 : -1;
  }
};

/// Analyses the combinatorics of `mesh` (indices must be valid: see TriangleMesh::validate).
/// O(F log F) time, O(F) memory. Thread-safe (reads only).
MeshTopology analyze_topology(const TriangleMesh& mesh);

}  // namespace pointsurf
