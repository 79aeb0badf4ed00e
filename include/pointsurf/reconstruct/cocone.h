// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Cocone surface reconstruction (Amenta, Choi, Dey and Leekha 2000), the single-Delaunay
// simplification of the Crust (reconstruct/crust.h): an interpolating mesh whose vertices are the
// input points.
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/reconstruct/delaunay_surface.h"
#include "pointsurf/reconstruct/reconstruction.h"

namespace pointsurf {

struct CoconeParams : DelaunaySurfaceParams {
  double cocone_angle_deg = 22.5;  // theta, in (0, 90): a Delaunay triangle is a candidate when its
                                   // dual Voronoi edge meets, at each of its three vertices, the
                                   // cocone {y : |angle(y - p, pole vector) - 90| <= theta}
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<CoconeParams>& fields();
  void validate() const;
};

/// Counts from each step of reconstruct_cocone, for reports (candidate_triangles: Delaunay
/// triangles passing the cocone test).
struct CoconeStats : DelaunaySurfaceStats {};

/// Reconstructs an interpolating triangle mesh by the cocone test:
///  1. 3D Delaunay triangulation of the samples (CGAL, exact predicates; coordinates are shifted
///     to a local origin first, so georeferenced input keeps its precision);
///  2. Voronoi poles (as voronoi_poles() in spatial/): for each sample p, the pole p+ is the
///     farthest Voronoi vertex (circumcenter of an incident tetrahedron); the pole vector
///     v_p = p+ - p approximates the normal line. For samples on the convex hull (unbounded
///     Voronoi cell, pole at infinity), v_p is the normal of the plane fitted to the 10 nearest
///     samples, signed by the mean outward normal of the incident hull facets;
///  3. a Delaunay triangle is a candidate when its dual Voronoi edge (a segment between two
///     circumcenters, or a ray for hull triangles) meets the cocone of each of its vertices;
///  4. manifold extraction (shared with the Crust): normal filtering, repeated pruning of triangles at sharp edges
///     (Amenta et al. 1998), then a walk over the outer side of each connected piece that keeps
///     the mesh edge-manifold and consistently oriented (a fold, a candidate turning back within
///     the sharp-edge wedge, joins only where nothing else can: through it the walk would orient
///     what lies beyond inside out); then triangles with a boundary edge longer than
///     `max_boundary_edge_in_spacings` that ends on the cloud's border (angular-gap test,
///     features/boundary_points.h) are peeled (rim slivers of open surfaces);
///  5. holes up to `max_hole_perimeter_in_spacings` local spacings (left by undersampling) are
///     closed by fill_holes() (reconstruct/fill_holes.h) with triangles of the samples.
/// Output: `mesh.vertices.positions` are the input points in input order with their colours and fields.
/// If the cloud has normals they are kept and each piece is oriented to agree with them;
/// otherwise each closed piece faces outward (positive volume), each open piece by the hull
/// pole vectors, and `mesh.vertices.normals` are the unit pole vectors, signed to agree with the
/// triangles (face normals where a sample has no finite pole). Triangles are counter-clockwise
/// seen from the side the normals point to. Guarantees: edge-manifold and oriented (not
/// necessarily vertex-manifold); no guarantee of closedness under undersampling, noise, sharp
/// edges or on the rim of open surfaces (rim samples whose hull normal is not the surface
/// normal are often left unused).
/// Errors: UsageError for parameters out of range (named with the value) or fewer than 4 points;
/// InputError for non-finite coordinates or normals of the wrong count; ComputeError when all
/// points are collinear or coplanar (no 3D Delaunay); CancelledError when `progress` returns
/// false. Exact duplicates are merged (the later copies stay as unused vertices).
/// Cost: O(N log N) expected time, about 1 KB memory per point (the Delaunay triangulation
/// dominates; measured 114 MB peak for 100k points); the triangulation is sequential (CGAL's
/// parallel insertion is compiled in with -DPOINTSURF_PARALLEL_DELAUNAY and libtbbmalloc, with
/// the same output), the other passes use oneTBB. Deterministic.
/// Thread-safe (reads `cloud` only). If `stats` is given it receives the stage counts.
ReconstructionResult reconstruct_cocone(const PointCloud& cloud, const CoconeParams& params = {},
                                       const ProgressCallback& progress = {}, CoconeStats* stats = nullptr);

}  // namespace pointsurf
