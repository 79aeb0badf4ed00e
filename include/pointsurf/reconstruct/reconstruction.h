// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What every surface reconstruction returns: the mesh and its topology, so that each method
// reports holes, manifoldness and components the same way.
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/core/results.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

/// Counts every method reports under the same names (the reconstruct stage writes them all to
/// the report), then the method's own counts by name.
struct ReconstructionStats {
  std::size_t input_points = 0;         // points given
  std::size_t duplicate_points = 0;     // exact duplicates of earlier points, left unused
  std::size_t candidate_triangles = 0;  // triangles the method proposed before choosing (ball
                                        // pivoting: the triangles the balls made)
  std::size_t holes_filled = 0;         // holes the shared hole filler closed (fill_holes)
  std::size_t fill_triangles = 0;       // triangles it added
  double seconds = 0.0;                 // wall time of the whole method
  std::vector<std::pair<std::string, std::size_t>> counts;  // the method's own counts, in report order
  std::vector<std::pair<std::string, double>> figures;      // and its own measures (seconds, lengths)

  /// The reported members (core/results.h) of a run of `method` (triangulate, cocone, crust,
  /// ball-pivot or poisson, the reconstruct stage's names): the counts every method reports,
  /// the method's own counts and figures (`counts` and `figures`, named in the order the
  /// method lists them), its time. std::logic_error for another name, and when recording
  /// stats that lack one of the method's names.
  static const ResultTable<ReconstructionStats>& results(const std::string& method);
};

struct ReconstructionResult {
  TriangleMesh mesh;           // interpolating methods: the input points (with their normals,
                               // colours and fields) as vertices; triangles counter-clockwise
                               // seen from the side the normals point to
  MeshTopology topology;       // analyze_topology(mesh): holes, non-manifold edges, components
  std::size_t unused_points = 0;  // input points that no triangle uses (smaller is better)
  double mean_spacing = 0.0;   // the cloud's mean spacing, from which the defaults were derived
  ReconstructionStats stats;   // the same counts from every method
};

}  // namespace pointsurf
