// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Crust surface reconstruction (Amenta, Bern and Kamvysselis 1998), in its single-Delaunay
// "cocone" form (Amenta, Choi, Dey and Leekha 2000): an interpolating mesh whose vertices are
// the input points.
#include <cstddef>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/reconstruct/reconstruction.h"

namespace pointsurf {

/// How the manifold extraction treats edges that only one candidate triangle uses.
enum class CrustBoundary {
  Auto,    // per connected piece: prune as Closed, and fall back to Open where that would erase
           // more than half of the piece (an open surface erodes away entirely when its rim
           // edges count as sharp)
  Closed,  // the surface is closed: rim edges are sharp and their triangles are pruned
  Open,    // the surface may have a boundary: only wedge-sharp edges are pruned
};

struct CrustParams {
  double cocone_angle_deg = 22.5;       // theta, in (0, 90): a Delaunay triangle is kept when its
                                        // dual Voronoi edge meets, at each of its three vertices,
                                        // the cocone {y : |angle(y - p, pole vector) - 90| <= theta}
  double normal_filter_angle_deg = 60.0;  // in (0, 90]: drop triangles whose normal makes a larger
                                        // angle (unsigned) with the pole vector of any of their
                                        // vertices; 90 disables the filter
  double sharp_edge_angle_deg = 270.0;  // in [180, 360]: an edge is sharp when two consecutive
                                        // triangles around it leave a gap larger than this (all
                                        // its triangles lie in a wedge < 360 - this); triangles at
                                        // sharp edges are pruned repeatedly; 360 disables
  CrustBoundary boundary = CrustBoundary::Auto;  // see CrustBoundary
  double max_boundary_edge_in_spacings = 4.0;  // >= 0, mean spacings: after the walk, triangles with a
                                        // boundary edge longer than this are peeled, repeatedly
                                        // (the long thin triangles Delaunay puts along the concave
                                        // parts of an open rim); a mesh without boundary edges is
                                        // untouched; 0: off
  int max_hole_edges = 16;              // >= 0: boundary loops of at most this many edges are closed
                                        // with triangles of the samples (ear clipping, no new
                                        // vertex); 0 (or 1, 2): off
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

/// Counts from each stage of reconstruct_crust, for reports.
struct CrustStats {
  std::size_t input_points = 0;        // points given
  std::size_t duplicate_points = 0;    // exact duplicates merged by the Delaunay triangulation
                                       // (they stay in the mesh as unused vertices)
  std::size_t delaunay_cells = 0;      // finite Delaunay tetrahedra
  std::size_t hull_points = 0;         // samples on the convex hull (pole at infinity)
  std::size_t cocone_triangles = 0;    // Delaunay triangles passing the cocone test
  std::size_t normal_filtered = 0;     // of those, removed by the normal filter
  std::size_t pruned = 0;              // removed by sharp-edge pruning
  std::size_t open_pieces = 0;         // connected pieces treated as open (CrustBoundary::Auto/Open)
  std::size_t closed_pieces = 0;       // connected pieces treated as closed
  std::size_t walk_dropped = 0;        // candidates the manifold walk left out
  std::size_t rim_peeled = 0;          // walked triangles then peeled at the boundary
  std::size_t holes_filled = 0;        // small boundary loops closed (CrustParams::max_hole_edges)
  std::size_t flipped_pieces = 0;      // pieces whose orientation the final outward test flipped
  double seconds_delaunay = 0.0;       // wall time of the 3D Delaunay triangulation
  double seconds_total = 0.0;          // wall time of the whole reconstruction
};

/// Reconstructs an interpolating triangle mesh with the Crust via the cocone test:
///  1. 3D Delaunay triangulation of the samples (CGAL, exact predicates; coordinates are shifted
///     to a local origin first, so georeferenced input keeps its precision);
///  2. Voronoi poles: for each sample p, the pole p+ is the farthest Voronoi vertex (circumcenter
///     of an incident tetrahedron); the pole vector v_p = p+ - p approximates the normal line.
///     For samples on the convex hull (unbounded Voronoi cell, pole at infinity), v_p is the normal
///     of the plane fitted to the 10 nearest samples, signed by the mean outward normal of the
///     incident hull facets (that mean alone lies sideways at the rim of an open surface);
///  3. a Delaunay triangle is a candidate when its dual Voronoi edge (a segment between two
///     circumcenters, or a ray for hull triangles) meets the cocone of each of its vertices;
///  4. manifold extraction: normal filtering, repeated pruning of triangles at sharp edges
///     (Amenta et al. 1998), then a walk over the outer side of each connected piece that keeps
///     the mesh edge-manifold and consistently oriented; then triangles with a boundary edge
///     longer than `max_boundary_edge_in_spacings` are peeled (rim slivers of open surfaces);
///  5. boundary loops of at most `max_hole_edges` edges (holes left by undersampling) are closed
///     by ear clipping with triangles of the samples, never reusing an existing edge.
/// Output: `mesh.vertices` are the input points in input order with their colours and fields.
/// If the cloud has normals they are kept and each piece is oriented to agree with them;
/// otherwise each closed piece faces outward (positive volume), each open piece by the hull
/// pole vectors, and `mesh.vertex_normals` are the unit pole vectors, signed to agree with the
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
ReconstructionResult reconstruct_crust(const PointCloud& cloud, const CrustParams& params = {},
                                       const ProgressCallback& progress = {}, CrustStats* stats = nullptr);

}  // namespace pointsurf
