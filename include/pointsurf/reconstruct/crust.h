// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The Crust (Amenta, Bern and Kamvysselis 1998, "A new Voronoi-based surface reconstruction
// algorithm"), two-pass as the paper has it: an interpolating mesh whose vertices are the input
// points. Its single-Delaunay simplification is the cocone (reconstruct/cocone.h).
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/reconstruct/delaunay_surface.h"
#include "pointsurf/reconstruct/reconstruction.h"

namespace pointsurf {

/// The Crust has no parameter of its own: only those of the shared manifold extraction.
struct CrustParams : DelaunaySurfaceParams {
  /// Throws UsageError naming the first value out of range.
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<CrustParams>& fields();
  void validate() const { DelaunaySurfaceParams::validate("crust"); }
};

/// Counts from each step of reconstruct_crust (candidate_triangles: triangles of the second
/// Delaunay triangulation whose three vertices are samples).
struct CrustStats : DelaunaySurfaceStats {
  std::size_t poles = 0;                     // distinct finite poles p+ and p- inserted
  std::size_t second_delaunay_vertices = 0;  // samples plus poles in the second triangulation
  std::size_t second_delaunay_cells = 0;     // its finite tetrahedra
};

/// Reconstructs an interpolating triangle mesh with the two-pass Crust:
///  1. 3D Delaunay triangulation of the samples (CGAL, exact predicates, about a local origin);
///  2. Voronoi poles of each sample (voronoi_poles() in spatial/): p+ the farthest vertex of its
///     Voronoi cell, p- the farthest on the other side; a hull sample has its p+ at infinity and
///     contributes p- only;
///  3. a second Delaunay triangulation of the samples together with all finite poles; its
///     triangles whose three vertices are samples are the candidates (the poles approximate the
///     medial axis, so a triangle survives only when its circumsphere holds no pole: the
///     surface's triangles, not those that cut through the inside or outside);
///  4. the manifold extraction shared with the cocone (normal filter against the pole vectors,
///     sharp-edge pruning, the walk over the outer side of each piece, rim peeling);
///  5. small holes closed as in reconstruct_cocone.
/// Against the cocone: the second triangulation costs about 3x the first's time and memory (up to
/// 3 N points), and the candidates differ where the sampling is coarse against the local feature
/// size (the Crust keeps a triangle whose circumsphere is empty of poles; the cocone one whose
/// Voronoi edge crosses the cocones): the Crust is the better of the two on undersampled thin
/// parts, the cocone the faster.
/// Output, errors, orientation and guarantees as reconstruct_cocone (messages prefixed "crust").
/// Deterministic; thread-safe (reads `cloud` only). If `stats` is given it receives the counts.
ReconstructionResult reconstruct_crust(const PointCloud& cloud, const CrustParams& params = {},
                                       const ProgressCallback& progress = {}, CrustStats* stats = nullptr);

}  // namespace pointsurf
