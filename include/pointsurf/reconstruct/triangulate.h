// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Region-growing triangulation of an oriented point cloud (SPEC C10): local Delaunay umbrellas
// in each point's tangent plane, merged into one edge-manifold, consistently oriented mesh,
// with a final pass that closes small holes.
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/reconstruct/fill_holes.h"
#include "pointsurf/reconstruct/reconstruction.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

struct TriangulateParams {
  int k = 30;                          // at most k neighbours per point, >= 3
  Length radius = Length::spacings(3.0);  // search radius and longest edge, > 0: cloud units, or
                                       // local spacings (each point's own local spacing)
  double max_offset_in_spacings = 1.25;// neighbours farther than this many local spacings from a
                                       // point's tangent plane are ignored; one whose normal
                                       // agrees with the point's may only lie 0.5 local spacings
                                       // off it, plus distance x sine of the normals' angle
                                       // (keeps parallel layers, e.g. a floor under a table, apart)
  double max_normal_angle_deg = 120.0; // neighbours whose normal deviates more are ignored
                                       // (opposite sides of a thin part), (0, 180]
  double min_angle_deg = 5.0;          // smallest accepted inner angle of a triangle, [0, 60)
  double max_angle_deg = 160.0;        // largest accepted inner angle, (60, 180]
  double max_dihedral_deg = 135.0;     // largest angle between the normals of two triangles
                                       // sharing an edge (135 keeps 90-degree CAD edges), (0, 180]
  double max_front_angle_deg = 150.0;  // after growing, boundary corners opening less than this
                                       // (hole side) are closed by a triangle, sharpest first,
                                       // when the new edge is at most twice the radius; 0: none,
                                       // [0, 180)
  double max_hole_perimeter_in_spacings = HoleFillParams{}.max_perimeter_in_spacings;  // holes (at most 64 corners) whose perimeter is
                                       // at most this many local spacings are closed at the end;
                                       // 0: none closed (nor pinches repaired)
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<TriangulateParams>& fields();
  /// Throws UsageError naming the first value outside the ranges above. The one place they
  /// are checked (reconstruct_region_growing and the pipeline call it).
  void validate() const;
};

struct TriangulateResult : ReconstructionResult {
  double local_spacing_mean = 0.0;       // mean of the per-point local spacings, cloud units
  std::size_t duplicate_points = 0;      // points coinciding with an earlier point: not used
  std::size_t candidate_triangles = 0;   // distinct triangles proposed by the umbrellas
  std::size_t selected_triangles = 0;    // triangles kept by the region growing
  std::size_t front_triangles = 0;       // triangles added where the front turned sharply
  std::size_t holes_filled = 0;          // small holes closed by the final pass (a hole reopened
                                         // and closed again counts each time)
  std::size_t fill_triangles = 0;        // triangles added to close them
  std::size_t pinch_triangles_removed = 0;  // triangles removed where fans touched at a vertex
  std::size_t inserted_points = 0;       // unused points inserted at the end into the triangle
                                         // or edge they project onto
};

/// Region-growing triangulation (SPEC C10; after Gopi, Krishnan and Silva 2000, "Surface
/// reconstruction based on lower dimensional localized Delaunay triangulation", and the greedy
/// projection of Marton, Rusu and Beetz 2009).
///
/// 1. Local spacing of each point: the mean distance to its 3 nearest distinct neighbours.
///    Exact duplicates (closer than 1e-9 of the mean spacing) are left out.
/// 2. Umbrella of each point p (in parallel, in the tree's spatial order): at most `k`
///    neighbours within `radius` (default 3 local spacings), dropping those farther than
///    `max_offset_in_spacings` local spacings from p's tangent plane (same-facing ones: farther
///    than 0.5 local spacings plus what the turn of the normals explains) or whose normal
///    deviates more than `max_normal_angle_deg`; each is mapped into the tangent plane keeping its 3D distance to
///    p (an unfolding that keeps sharp CAD edges apart), and the 2D Delaunay neighbours of p
///    are found by clipping p's Voronoi cell with their bisectors. Consecutive Delaunay
///    neighbours give triangles around p, counter-clockwise seen from p's normal side; each is
///    kept when its edges are at most the radius, its inner angles within [min_angle_deg,
///    max_angle_deg], and its normal on the side of all three vertex normals.
/// 3. Region growing (serial): the candidates, ranked by how many of their three umbrellas
///    proposed them and then by smallest angle, seed regions that grow across their edges,
///    best candidate first. A triangle is accepted when none of its directed edges is used yet
///    (every edge then has at most two triangles, traversed in opposite directions:
///    edge-manifold and consistently oriented by construction), when at each vertex already in
///    the mesh it continues that vertex's fan across an edge and fits into the fan's gap (no
///    overlap), and when the angle to each neighbouring triangle's normal is at most
///    `max_dihedral_deg`. Remaining candidates sharing an edge with the mesh then bridge fronts
///    that met out of step, and boundary corners sharper than `max_front_angle_deg` are closed.
/// 4. Holes with at most 64 corners whose perimeter is at most
///    `max_hole_perimeter_in_spacings` local spacings are closed by dynamic programming over the
///    loop (Liepa 2003): the triangulation whose new edges are not in the mesh yet, whose
///    triangles face the way their corners' normals do, with the smallest worst normal
///    deviation, then the smallest area. Loops through a pinched vertex (fans touching at a
///    vertex) are split there. Then, up to 3 times: the minor fans at pinched vertices and the
///    triangles along small holes that had no valid filling (folds) are removed, and the holes
///    this opens (up to 3x the perimeter limit) are closed again. Larger holes remain open and
///    are reported in `topology.boundary_loops` (corner list and perimeter).
/// 5. Points no triangle uses are inserted into the triangle (split in 3) or interior edge
///    (its two triangles split in 2) they project onto, within the search radius.
///
/// `cloud` needs oriented unit normals (N×3; estimate_normals + orient_normals); points with a
/// zero normal are left unused. The mesh's vertices are the cloud's points with all their
/// attributes; triangles are counter-clockwise seen from the side the normals point to.
/// Reuses `tree` if given (built over `cloud.positions`). Memory O(k N). Throws UsageError for
/// fewer than 3 points, missing normals or a parameter out of range; CancelledError when
/// `progress` returns false. Thread-safe for distinct outputs (reads `cloud` only).
TriangulateResult reconstruct_region_growing(const PointCloud& cloud, const TriangulateParams& params = {},
                                             const KdTree* tree = nullptr, const ProgressCallback& progress = {});

}  // namespace pointsurf
