// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The steps that the cocone reconstruction and the Crust share (src/reconstruct/
// delaunay_surface.cpp): the input checks and the first Delaunay triangulation with its Voronoi
// poles, then the manifold extraction of their candidate triangles.
#include <array>
#include <cstdint>
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

/// Candidate triangles with their edge incidences (CSR: edge e, the pair edge_verts[e] (smaller
/// index first), has the triangles edge_tris[edge_start[e] .. edge_start[e + 1])).
struct CandidateComplex {
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<int, 3>> tri_edges;  // edge id of (tris[t][k], tris[t][k + 1])
  std::vector<std::array<int, 2>> edge_verts;
  std::vector<std::size_t> edge_start;
  std::vector<int> edge_tris;
};

/// The phases of extract_delaunay_surface (below) over their shared state, each runnable alone
/// on state that the phases before it (or a test) set up. Run in the order declared; the
/// public function reports progress between them.
class DelaunayExtraction {
public:
  DelaunayExtraction(const PointCloud& cloud, const DelaunaySetup& setup, std::vector<std::array<int, 3>> candidates,
                     const DelaunaySurfaceParams& params, DelaunaySurfaceStats& stats);

  /// Reads candidates and the pole vectors; drops degenerate triangles and those whose normal
  /// strays from a vertex's pole vector (the survivors keep their order); stats.normal_filtered.
  void filter_by_normals();
  /// Reads candidates (moved out); produces cx, the triangles with their edges, and alive (all 1).
  void index_edges();
  /// Reads cx and alive; clears alive at sharp edges (and rims for closed pieces; per piece for
  /// DelaunayBoundary::Auto); stats.pruned, and open_pieces/closed_pieces under Auto.
  void prune_sharp_edges();
  /// Reads alive; produces the connected pieces: piece_count, piece_start and piece_tris (CSR of
  /// triangle ids, ascending in each piece); open/closed_pieces under Open/Closed.
  void split_pieces();
  /// Reads the pieces; walks each over its outer side from a seed facing +x: out_tris
  /// (oriented, grouped by piece), out_piece, out_src, edge_used; stats.walk_dropped.
  void walk_pieces();
  /// Reads out_* and edge_used; peels rim triangles with a too-long boundary edge with an end on
  /// the cloud's border, updating out_* and edge_used; stats.rim_peeled.
  void peel_rim();
  /// Reads out_* (and cloud normals or the poles); flips the pieces facing inwards in out_tris;
  /// stats.flipped_pieces.
  void orient_pieces();
  /// Reads out_tris (moved out) and the poles; produces reconstruction.mesh through the input
  /// points, with vertex normals from the signed pole vectors when the cloud has none.
  void build_mesh();
  /// Reads reconstruction.mesh; closes its small holes (fill_holes) and fills its topology and
  /// unused_points and the stats' hole counts.
  void fill_small_holes();
  /// The reconstruction built by the phases.
  ReconstructionResult result() && { return std::move(reconstruction); }

  const PointCloud& cloud;
  const DelaunaySetup& setup;
  const DelaunaySurfaceParams& params;
  DelaunaySurfaceStats& stats;
  double max_gap = 0.0;  // params.sharp_edge_angle_deg, radians

  std::vector<std::array<int, 3>> candidates;
  CandidateComplex cx;
  std::vector<char> alive;  // per triangle of cx: survives the filters so far
  int piece_count = 0;
  std::vector<std::size_t> piece_start;
  std::vector<int> piece_tris;
  std::vector<std::array<int, 2>> edge_used;  // per edge of cx: the accepted triangles (-1: none)
  std::vector<std::array<int, 3>> oriented;   // per triangle of cx: its orientation once tried
  std::vector<std::int8_t> state;             // per triangle of cx: 0 untried, 1 accepted, -1 rejected
  std::vector<Triangle> out_tris;
  std::vector<int> out_piece;  // piece of each output triangle
  std::vector<int> out_src;    // candidate triangle of each output triangle
  ReconstructionResult reconstruction;

private:
  int seed_of(int k) const;
  void walk_from(int k, int seed);
  void join_across(int t, const std::array<int, 3>& ot, int j);
  bool try_accept(int t, const std::array<int, 3>& o);
  bool directed(int t, int a, int b) const;
  int edge_of(int t, int a, int b) const;
  double orientation_score(std::size_t begin, std::size_t end) const;

  std::vector<int> bfs_;
  std::vector<double> ang_;
  std::vector<int> live_;
  std::vector<std::size_t> rank_;
};

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
