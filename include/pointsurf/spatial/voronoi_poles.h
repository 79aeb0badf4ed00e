// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Voronoi poles of a point sample (Amenta, Bern, Kamvysselis 1998): the farthest vertices of each
// sample's Voronoi cell, on either side of the surface. They approximate the medial axis, so the
// distance from a sample to the nearest pole estimates its local feature size, and the pole
// vector approximates the normal line. The Crust and the cocone reconstruction are built on them.
#include <cstddef>
#include <span>
#include <vector>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf {

struct VoronoiPoles {
  std::vector<Vector3d> positive;  // p+: the farthest Voronoi vertex of the sample's cell; NaN
                                   // when the cell is unbounded (a sample on the convex hull)
  std::vector<Vector3d> negative;  // p-: the farthest Voronoi vertex on the other side of the
                                   // sample ((p- - p) . axis < 0); NaN when there is none
  std::vector<Vector3d> axis;      // unit pole vector: (p+ - p) normalized; for hull samples the
                                   // normal of the plane through the 10 nearest samples, signed
                                   // outward by the mean normal of the sample's hull facets; zero
                                   // for a duplicate point
  std::vector<char> on_hull;       // 1 where the Voronoi cell is unbounded
  std::size_t hull_points = 0;     // samples on the convex hull
  std::size_t duplicate_points = 0;  // exact duplicates of an earlier point: their entries are
                                   // NaN / zero
  std::size_t delaunay_cells = 0;  // finite Delaunay tetrahedra (Voronoi vertices)
};

/// The Voronoi poles of `points` (input coordinates in, input coordinates out; computed about the
/// bounding-box centre, so georeferenced coordinates keep their precision), from CGAL's 3D
/// Delaunay triangulation with exact predicates.
/// Errors: UsageError for fewer than 4 points; InputError for a non-finite coordinate (naming the
/// point); ComputeError when all points are coplanar, collinear or equal.
/// Cost: O(N log N) expected time, about 1 KB per point while the triangulation exists; the pole
/// pass runs in parallel (oneTBB). Deterministic. Thread-safe.
VoronoiPoles voronoi_poles(std::span<const Vector3d> points);

}  // namespace pointsurf
