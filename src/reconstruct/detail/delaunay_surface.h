// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The steps that the cocone reconstruction and the Crust share (src/reconstruct/
// delaunay_surface.cpp): the input checks and the first Delaunay triangulation with its Voronoi
// poles, then the manifold extraction of their candidate triangles.
#include <array>
#include <vector>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/reconstruct/delaunay_surface.h"
#include "pointsurf/reconstruct/reconstruction.h"
#include "spatial/detail/delaunay_3.h"

namespace pointsurf::detail {

/// The fields of DelaunaySurfaceParams into the table of P (DelaunaySurfaceParams or a struct
/// derived from it: the cocone's and the Crust's), so each method's table names them once.
template <class P>
void add_delaunay_fields(FieldTable<P>& t) {
  using B = DelaunaySurfaceParams;
  t.number("normal_filter_angle_deg", static_cast<double P::*>(&B::normal_filter_angle_deg),
           "Drop triangles deviating more from the pole vectors; 90: off")
      .unit("degrees")
      .range(0, 90, true, false);
  t.number("sharp_edge_angle_deg", static_cast<double P::*>(&B::sharp_edge_angle_deg), "Sharp-edge pruning gap; 360: off")
      .unit("degrees")
      .range(180, 360);
  t.choice("boundary", static_cast<DelaunayBoundary P::*>(&B::boundary), delaunay_boundary_names(),
           "Surface kind: auto (per piece), closed or open");
  t.number("max_boundary_edge_in_spacings", static_cast<double P::*>(&B::max_boundary_edge_in_spacings),
           "Peel rim triangles with a longer boundary edge; 0: off")
      .unit("mean spacings")
      .non_negative();
  t.number("max_hole_perimeter_in_spacings", static_cast<double P::*>(&B::max_hole_perimeter_in_spacings),
           "Close holes up to this perimeter (fill_holes, every interpolating method); 0: none")
      .unit("local spacings")
      .non_negative();
}

/// The samples about a local origin, their Delaunay triangulation and poles.
struct DelaunaySetup {
  Vector3d origin = Vector3d::Zero();  // bounding-box centre of the input
  std::vector<Vector3d> p;             // input positions minus origin
  double spacing = 0.0;                // mean spacing
  DelaunayCells cells;
  PoleSet poles;
};

/// Checks `cloud` (UsageError below 4 points or above 2^29, InputError for a non-finite
/// coordinate, ComputeError when coplanar or collinear; `method` names the caller in each
/// message), shifts it to a local origin, triangulates it and computes the poles. Fills the
/// input, duplicate, cell and hull counts and seconds_delaunay of `stats`.
DelaunaySetup prepare_delaunay(const PointCloud& cloud, const char* method, DelaunaySurfaceStats& stats,
                               ProgressReporter& reporter);

/// Manifold extraction of the candidate triangles (each a sorted triple of sample indices, no
/// duplicates): normal filter, sharp-edge pruning, the walk over the outer side of each piece,
/// rim peeling, orientation, small-hole filling; then the mesh through the input points with
/// the input's attributes (vertex normals from the signed pole vectors when the cloud has none).
ReconstructionResult extract_delaunay_surface(const PointCloud& cloud, const DelaunaySetup& setup,
                                              std::vector<std::array<int, 3>> candidates,
                                              const DelaunaySurfaceParams& params, DelaunaySurfaceStats& stats,
                                              ProgressReporter& reporter);

/// The counts of `stats` as the ReconstructionStats every method fills (the extraction's own in
/// its counts, `extra` appended).
ReconstructionStats common_stats(const DelaunaySurfaceStats& stats, std::vector<std::pair<std::string, std::size_t>> extra = {});

}  // namespace pointsurf::detail
