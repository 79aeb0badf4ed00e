// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The 3D Delaunay triangulation as plain arrays, and the Voronoi poles computed from it. CGAL is
// included by src/spatial/delaunay_3.cpp only: the triangulation is copied into these arrays
// right after it is built, and every later pass (poles, cocone test, Crust) works on them.
#include <array>
#include <cstddef>
#include <vector>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf {
class KdTree;
}

namespace pointsurf::detail {

constexpr int kInfiniteVertex = -1;

/// Cell c has vertices vertex[c] (kInfiniteVertex for the point at infinity) and neighbor[c][i]
/// across the facet opposite vertex i. For a finite cell, `center` is its circumcenter (NaN for
/// a flat cell); for an infinite cell, the unit outward normal of its hull facet. Cells are
/// numbered in the order of their sorted vertex indices, so every later pass is deterministic
/// whatever order the (parallel) insertion left them in.
struct DelaunayCells {
  std::vector<std::array<int, 4>> vertex;
  std::vector<std::array<int, 4>> neighbor;
  std::vector<Vector3d> center;
  std::vector<char> infinite;
  std::vector<int> representative;  // input index -> the vertex kept for it (itself unless an
                                    // exact duplicate of a point of smaller index)
  std::size_t duplicates = 0;       // input points merged into an earlier one
  std::size_t finite_cells = 0;
  int dimension = 3;                // the triangulation's dimension; the arrays are empty below 3
  std::size_t size() const { return vertex.size(); }
};

/// Delaunay triangulation of `points` (local coordinates: the caller shifts georeferenced input
/// to a local origin first). CGAL's exact predicates; spatially sorted insertion, in parallel
/// when built with POINTSURF_PARALLEL_DELAUNAY. Returns dimension < 3 (and no cells) when the
/// points are coplanar, collinear or all equal.
DelaunayCells delaunay_cells(const std::vector<Vector3d>& points);

/// Voronoi poles of the samples of a Delaunay triangulation (Amenta, Bern, Kamvysselis 1998).
/// For a sample p with a bounded Voronoi cell, the positive pole p+ is its farthest Voronoi
/// vertex (circumcenter of an incident cell) and the negative pole p- the farthest one on the
/// other side (v_p . (p- - p) < 0, with v_p = p+ - p). A sample on the convex hull has its p+ at
/// infinity: `axis` is then the normal of the plane fitted to its 10 nearest samples, signed by
/// the mean outward normal of its hull facets (that mean alone lies sideways at the rim of an
/// open surface), and p- the farthest Voronoi vertex against that axis.
struct PoleSet {
  std::vector<Vector3d> axis;         // unit pole vector (zero: none, e.g. a duplicate)
  std::vector<Vector3d> positive;     // p+ (NaN when at infinity or none)
  std::vector<Vector3d> negative;     // p- (NaN when none)
  std::vector<Vector3d> hull_normal;  // unit mean outward hull-facet normal (hull samples), else zero
  std::vector<char> on_hull;          // the sample's Voronoi cell is unbounded
  std::vector<char> finite_pole;      // p+ is a finite Voronoi vertex
  std::size_t hull_points = 0;
};

/// Poles of every representative sample, in parallel in the tree's spatial order. `tree` is
/// built over `points` (the same local coordinates the triangulation was built from).
PoleSet voronoi_poles(const DelaunayCells& cells, const std::vector<Vector3d>& points, const KdTree& tree);

}  // namespace pointsurf::detail
