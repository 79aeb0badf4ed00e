// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Mesh quality: the combinatorics (core/mesh_topology.h) plus what needs geometry: degenerate
// and duplicate faces, self-intersections, triangle angles and aspect ratios, area, volume.
#include <cstddef>
#include <vector>

#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/triangle_mesh.h"
#include "pointsurf/evaluate/deviation_stats.h"

namespace pointsurf {

class TriangleBvh;

struct MeshQuality {
  MeshTopology topology;                   // counts, manifoldness, orientation, loops, components
  bool edge_manifold = false;              // no edge with three or more triangles
  bool vertex_manifold = false;            // every vertex fan one disc or half-disc
  bool oriented = false;                   // neighbours traverse shared edges oppositely
  bool closed = false;                     // no boundary edge
  bool watertight = false;                 // closed, manifold, oriented (MeshTopology::watertight)
  long genus = -1;                         // MeshTopology::genus(); -1: undefined
  std::size_t degenerate_faces = 0;        // repeated vertex index or zero area
  std::size_t duplicate_faces = 0;         // faces over the same three vertices as an earlier one
  std::size_t self_intersections = 0;      // pairs of triangles sharing no vertex that cross (0 is better)
  double area = 0.0;                       // square cloud units
  double volume = 0.0;                     // enclosed volume when closed (cubic cloud units); else 0
  bool has_volume = false;                 // volume is defined (closed and oriented)
  ValueDistribution angles_deg;            // inner angles of the non-degenerate faces, 18 bins of 10 degrees
  ValueDistribution aspect_ratios;         // longest edge x perimeter / (4 sqrt 3 area): 1 equilateral, larger worse

  /// The reported members: key, unit, which way is better, doc (core/results.h).
  static const ResultTable<MeshQuality>& results();
};

/// The quality of `mesh`. Throws InputError when an index is out of range or a vertex used by a
/// face is not finite. Parallel where it matters (self-intersections); thread-safe.
/// O(F log F). `bvh` may be a hierarchy over the mesh already built. `progress` hears the
/// phases (topology, geometry, self-intersections) and fractions through the self-intersection
/// pass; its false answer throws CancelledError.
MeshQuality analyze_mesh_quality(const TriangleMesh& mesh, const TriangleBvh* bvh = nullptr, const ProgressCallback& progress = {});

/// Pairs of triangles that share no vertex and intersect (touching counts; coplanar overlaps
/// are not detected). Parallel; thread-safe. `progress` as above.
std::size_t count_self_intersections(const TriangleMesh& mesh, const TriangleBvh& bvh, const ProgressCallback& progress = {});

}  // namespace pointsurf
