// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Screened Poisson surface reconstruction (Kazhdan, Bolitho, Hoppe: "Poisson Surface
// Reconstruction", SGP 2006; Kazhdan, Hoppe: "Screened Poisson Surface Reconstruction", ACM TOG
// 32(3), 2013), on an adaptive octree, with PoissonRecon's density output and trimming.
#include <cstddef>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/reconstruct/reconstruction.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

enum class PoissonBoundary {
  Neumann,    // zero normal derivative on the bounding cube (PoissonRecon's default)
  Dirichlet,  // zero value on the bounding cube
};
/// "neumann", "dirichlet".
const EnumNames<PoissonBoundary>& poisson_boundary_names();

struct PoissonParams {
  // Finest octree level: the cube around the points (1.1 x their largest extent) is split in
  // 2^depth cells per axis. 0 (default): from the data, the level whose cell is closest to the
  // mean spacing, clamped to [6, 10]. At most 16.
  int depth = 0;
  // Levels 1..full_depth are complete grids (default 5, PoissonRecon's); deeper levels exist
  // only around the samples. Clamped to depth.
  int full_depth = 5;
  // Density estimate: the (fractional) depth at which a node holds this many samples is the
  // density reported per vertex (default 1.5, PoissonRecon's --samplesPerNode).
  double samples_per_node = 1.5;
  // Screening weight alpha: how strongly the function is pulled to the iso-value at the samples
  // (default 4, PoissonRecon's: twice the B-spline degree); 0: plain Poisson.
  double point_weight = 4.0;
  PoissonBoundary boundary = PoissonBoundary::Neumann;
  // Weight each sample by its normal's length (the scanner's confidence); default off: every
  // normal counts as unit length. Zero and non-finite normals are skipped either way.
  bool weight_by_normal_length = false;
  // Trimming (PoissonRecon's SurfaceTrimmer): remove the surface where the density is below
  // this depth (depth units, e.g. 7 for a depth-10 reconstruction); 0 (default): off.
  double trim_depth = 0.0;
  // ... then remove the pieces whose area is below this share of the largest piece's (default
  // 0.001, SurfaceTrimmer's --aRatio). Used only when trimming.
  double island_area_ratio = 0.001;
  // Remove the pieces whose samples per area (the samples within two finest cells of the mesh,
  // each counted at its nearest vertex) are more than this many depth units below the largest
  // piece's (each unit: 4 times fewer): the bubbles that clusters of outliers raise away from the
  // surface, which hold only those outliers. A second object scanned like the first keeps its
  // density and stays. Independent of samples_per_node. Default 2; 0: keep every piece.
  double unsupported_piece_gap = 2.0;
  // Vertex placement on each edge crossing of the extracted surface: 0 linear in the corner
  // values; 1 (default) the quadratic through the edge's midpoint, exact for this function (along
  // a lattice edge it is one quadratic piece); more: further false-position steps.
  int root_refinement_steps = 1;
  // Conjugate-gradient iterations per level below full_depth at most (default 8); the complete
  // levels get at least 100. Each level stops when its residual fell by `tolerance`.
  int max_iterations = 8;
  double tolerance = 1e-3;
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<PoissonParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

struct PoissonResult : ReconstructionResult {
  int depth = 0;                               // the finest level used
  std::vector<std::size_t> nodes_per_level;    // [level], level 0 unused: B-spline functions
  std::vector<int> iterations_per_level;       // conjugate-gradient iterations per level
  std::vector<double> residual_per_level;      // final / initial residual per level (smaller is better)
  double iso_value = 0.0;                      // the weighted mean of the function at the samples
  std::size_t skipped_normals = 0;             // samples left out: zero or non-finite normal
  std::size_t unsupported_pieces = 0;          // pieces removed by unsupported_piece_gap
  std::size_t unsupported_triangles = 0;       // and their triangles
  std::size_t trimmed_triangles = 0;           // triangles removed by trimming (below the density level)
  std::size_t peak_bytes = 0;                  // octree, coefficients and per-sample arrays at their largest
};

/// A watertight surface approximating the oriented points of `cloud`: the level set of the
/// function whose gradient best matches the normals (outward) and which is screened towards
/// its iso-value at the samples. Each level of the octree solves for its B-splines (degree 2)
/// given the coarser levels' solution (cascadic, conjugate gradients), parallel with oneTBB.
/// The mesh's vertices carry normals from the function's gradient, a `density` field (depth
/// units: see PoissonParams::samples_per_node), and the colour and scalar fields of the
/// nearest sample. The result is the same (up to rounding) for any order of the points and
/// under a translation: coordinates are taken relative to the bounding box's centre.
///
/// `cloud`: N points with normals (N×3); colours and fields optional. `tree`: a KdTree over
/// cloud.positions to reuse (one is built when null). `progress`: fraction done in [0, 1];
/// returning false throws CancelledError.
///
/// Throws UsageError for bad parameters or a cloud without normals; InputError for a
/// non-finite coordinate or fewer than 4 points with a usable (non-zero, finite) normal.
/// Memory about 100 bytes per octree node plus 250 bytes per sample; the result reports it.
/// Thread-safe: reads its inputs only.
PoissonResult reconstruct_poisson(const PointCloud& cloud, const PoissonParams& params = {}, const KdTree* tree = nullptr,
                                  const ProgressCallback& progress = {});

}  // namespace pointsurf
