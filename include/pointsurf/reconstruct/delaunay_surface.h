// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What the two Delaunay-based reconstructions (Crust and cocone) share: the manifold extraction
// that turns their candidate triangles into an edge-manifold, oriented mesh, its parameters and
// its counts.
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/reconstruct/fill_holes.h"

namespace pointsurf {

/// How the manifold extraction treats edges that only one candidate triangle uses.
enum class DelaunayBoundary {
  Auto,    // per connected piece: prune as Closed, and fall back to Open where that would erase
           // more than half of the piece (an open surface erodes away entirely when its rim
           // edges count as sharp)
  Closed,  // the surface is closed: rim edges are sharp and their triangles are pruned
  Open,    // the surface may have a boundary: only wedge-sharp edges are pruned
};
/// "auto", "closed", "open".
const EnumNames<DelaunayBoundary>& delaunay_boundary_names();

/// Parameters of the manifold extraction (Amenta, Bern, Kamvysselis 1998, section 4.2).
struct DelaunaySurfaceParams {
  double normal_filter_angle_deg = 60.0;  // in (0, 90]: drop triangles whose normal makes a larger
                                        // angle (unsigned) with the pole vector of any of their
                                        // vertices; 90 disables the filter
  double sharp_edge_angle_deg = 270.0;  // in [180, 360]: an edge is sharp when two consecutive
                                        // triangles around it leave a gap larger than this (all
                                        // its triangles lie in a wedge < 360 - this); triangles at
                                        // sharp edges are pruned repeatedly, and the walk takes
                                        // a triangle turning back within that wedge from its
                                        // neighbour (a fold) only where nothing else joins; 360
                                        // disables both
  DelaunayBoundary boundary = DelaunayBoundary::Auto;  // see DelaunayBoundary
  double max_boundary_edge_in_spacings = 4.0;  // >= 0, mean spacings: after the walk, triangles with a
                                        // boundary edge longer than this with an end on the cloud's
                                        // border (features/boundary_points.h) are peeled, repeatedly
                                        // (the long thin triangles Delaunay puts along the concave
                                        // parts of an open rim); a mesh without boundary edges, and
                                        // the rims of holes inside the cloud, are untouched; 0: off
  double max_hole_perimeter_in_spacings = HoleFillParams{}.max_perimeter_in_spacings;  // >= 0:
                                        // holes up to this perimeter (local spacings) are closed by
                                        // fill_holes() with triangles of the samples; 0: off
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<DelaunaySurfaceParams>& fields();
  /// Throws UsageError naming the first value out of range (`method` prefixes the message).
  void validate(const char* method) const;
};

/// Counts from each step, for reports.
struct DelaunaySurfaceStats {
  std::size_t input_points = 0;        // points given
  std::size_t duplicate_points = 0;    // exact duplicates merged by the Delaunay triangulation
                                       // (they stay in the mesh as unused vertices)
  std::size_t delaunay_cells = 0;      // finite Delaunay tetrahedra of the samples
  std::size_t hull_points = 0;         // samples on the convex hull (pole at infinity)
  std::size_t candidate_triangles = 0; // triangles proposed by the method (before the filter)
  std::size_t normal_filtered = 0;     // of those, removed by the normal filter
  std::size_t pruned = 0;              // removed by sharp-edge pruning
  std::size_t open_pieces = 0;         // connected pieces treated as open (Auto/Open)
  std::size_t closed_pieces = 0;       // connected pieces treated as closed
  std::size_t walk_dropped = 0;        // candidates the manifold walk left out
  std::size_t rim_peeled = 0;          // walked triangles then peeled at the boundary
  std::size_t holes_filled = 0;        // small holes closed (fill_holes, max_hole_perimeter_in_spacings)
  std::size_t fill_triangles = 0;      // triangles fill_holes added
  std::size_t fill_triangles_removed = 0;  // triangles fill_holes removed at pinched vertices and folds
  std::size_t flipped_pieces = 0;      // pieces whose orientation the final outward test flipped
  double seconds_delaunay = 0.0;       // wall time of the 3D Delaunay triangulation(s)
  double seconds_total = 0.0;          // wall time of the whole reconstruction
};

}  // namespace pointsurf
