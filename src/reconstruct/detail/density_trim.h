// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Trimming a reconstructed surface by a per-vertex field (the Poisson `density`), with the
// semantics of PoissonRecon's SurfaceTrimmer (Kazhdan): the field is smoothed, every triangle is
// cut along the field's level line at `level`, the part below is removed, then islands are
// settled against the total area: a kept component smaller than island_area_ratio x total is
// removed, and a removed component (a hole) smaller than that is put back.
#include <cstddef>
#include <string_view>

#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf::detail {

struct TrimResult {
  std::size_t cut_triangles = 0;      // triangles the level line crossed (split in two parts)
  std::size_t removed_triangles = 0;  // input triangles no part of which is kept
  std::size_t removed_islands = 0;    // components above the level removed as too small
  std::size_t filled_holes = 0;       // components below the level kept as too small
};

/// Keeps the part of `mesh` where the vertex field `field` (linearly interpolated over each
/// triangle, after `smooth_iterations` rounds of replacing each vertex's value by the mean of its
/// edge neighbours' values) is >= `level`, then removes kept components whose area is below
/// island_area_ratio x the total area and keeps removed ones below it (0: no island rule).
/// Vertices created on cut edges interpolate every vertex attribute (normals renormalised, fields
/// from the unsmoothed values); the pieces of a cut triangle inherit its face fields; unused
/// vertices are dropped. A manifold, consistently oriented input stays so. Throws InputError when
/// the field is missing and UsageError for a negative ratio or iteration count.
/// O(F) time and memory; not thread-safe on the same mesh.
TrimResult trim_by_vertex_field(TriangleMesh& mesh, std::string_view field, double level,
                                double island_area_ratio = 0.001, int smooth_iterations = 5);

}  // namespace pointsurf::detail
