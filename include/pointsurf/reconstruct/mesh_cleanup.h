// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Clean-up of a reconstructed mesh: small disconnected pieces ("specks") left where the
// surface could not be grown, e.g. 220 of the 475 components of building.ply have at most two
// triangles.
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/results.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

struct SmallComponentParams {
  double min_share = 0.001;  // smallest component kept, as a share of all faces, [0, 1]; 0.001
                             // (0.1 %, issue 12) drops specks of one or two triangles from a
                             // mesh of more than 2000 faces while a real part of a scan keeps
                             // far more faces than that; 0: keep all
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<SmallComponentParams>& fields();
  /// Throws UsageError when min_share is outside [0, 1].
  void validate() const;
};

struct SmallComponentsResult {
  std::size_t components = 0;          // edge-connected components before (see MeshTopology)
  std::size_t components_removed = 0;  // of them removed
  std::size_t faces_removed = 0;       // triangles removed with them (fewer is better)
  std::size_t min_faces = 0;           // smallest component kept, faces: ceil(min_share x F)

  /// The reported members (core/results.h).
  static const ResultTable<SmallComponentsResult>& results();
};

/// Removes from `mesh` every edge-connected component (triangles sharing an edge, as in
/// analyze_topology) with fewer than min_share x F faces, F the triangle count (min_share 0
/// removes nothing). The remaining triangles keep their order, and every face field is
/// filtered with them; the vertices and their attributes stay (those of removed faces become
/// unused), so vertex indices into a source cloud remain valid. O(F log F) time (parallel
/// sort), O(F) memory. Throws UsageError for a share out of range, InputError for an invalid
/// mesh. Not thread-safe on one mesh (modifies it).
SmallComponentsResult remove_small_components(TriangleMesh& mesh, const SmallComponentParams& params = {});

}  // namespace pointsurf
