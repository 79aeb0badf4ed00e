// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Topological noise: the small handles and tunnels a reconstruction leaves where two sheets of
// the surface come close (screened Poisson gave genus 14 on a genus-0 statue sample). A handle
// is short when one of its non-separating loops is at most `max_loop_in_spacings` spacings
// long; real handles (a torus, a mug's handle, the kitten's tail) have far longer loops and are
// left alone.
//
//   HandleParams params;                    // loops up to 10 spacings, removed
//   params.spacing = cloud_mean_spacing;    // 0: the mean edge length of the mesh
//   const HandleResult r = remove_short_handles(mesh, params);
//   // r.handles_before 14, r.handles_removed 13, r.handles_after 1 (the kitten's tail)
#include <cstddef>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/results.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

struct HandleParams {
  double max_loop_in_spacings = 10.0;  // >= 0: a handle is short when a non-separating loop of it
                                       // is at most this many spacings long (issue 28: 10 sample
                                       // spacings); 0: none looked for
  double spacing = 0.0;                // >= 0, cloud units: the spacing (the stage passes the
                                       // cloud's mean spacing); 0: the mean edge length
  bool remove = true;                  // cut each short handle along its loop and close both sides;
                                       // false: only count them
  /// Key, unit, range and doc of each field (core/fields.h); `spacing` is not exposed.
  static const FieldTable<HandleParams>& fields();
  /// Throws UsageError naming the value when one is negative or not finite.
  void validate() const;
};

/// One short loop found: the vertices in order (first not repeated) and its length.
struct HandleLoop {
  std::vector<int> vertices;
  double length = 0.0;  // cloud units
};

struct HandleResult {
  long handles_before = -1;        // genus summed over the components (MeshTopology::handles());
                                   // -1 where undefined (non-manifold or inconsistent edges)
  std::size_t short_handles = 0;   // short handles found (with remove: those removed and those left)
  std::size_t handles_removed = 0;
  long handles_after = -1;         // as handles_before, after the removal
  double max_loop_length = 0.0;    // the limit used, cloud units
  double shortest_loop = 0.0;      // length of the shortest loop found; 0 when none
  std::vector<HandleLoop> loops;   // the loops found, each once (on the input mesh when counting;
                                   // with remove, the loops cut)

  /// The reported members (core/results.h).
  static const ResultTable<HandleResult>& results();
};

/// Finds the short handles of `mesh` and, with params.remove, cuts each along its short loop and
/// closes both sides with triangles of the loop's own vertices (no vertex is added or moved;
/// vertex indices into a source cloud stay valid; face fields are dropped when triangles change).
///
/// Method (after Guskov and Wood 2001, "Topological noise removal"): from seeds covering the
/// surface (every vertex within an eighth of the limit of one), a geodesic ball is grown
/// (Dijkstra over the edges) to 5/8 of the limit. Whenever a vertex joins the ball touching it
/// along two or more separate arcs of its ring, a loop closes through it; the loop is a handle's
/// when the unreached vertices on its two sides are still connected (a breadth-first search
/// from both sides, stopped when either is exhausted): separating loops, around a thin limb or
/// a pocket, are left. A loop is kept when at most the limit long. Each hole is closed by a
/// virtual vertex for the search (the surface is seen as the closed one of the same genus);
/// balls grow over manifold, consistently oriented vertices, borders included, and stop at
/// non-manifold places and at the rims of holes that pass one. A loop that runs along a hole
/// is counted but not cut (neither side is all triangles). Removal: the faces on one side of the loop are removed and the two loops this leaves
/// are closed by the minimum-area triangulation of their corners (Barequet and Sharir 1995; at
/// most 256 corners a loop: a longer loop is reported, not cut);
/// removals that do not lower the genus by one each, or that leave a non-manifold edge, are
/// undone. Up to 4 rounds. Cost: about 30 Dijkstra steps per vertex for the default limit, plus
/// the searches on the sides of each closed loop. Throws UsageError for a parameter out of
/// range, InputError for an invalid mesh. Not thread-safe on one mesh (modifies it).
/// `progress` hears fractions through the searches (the first, over the whole surface, is
/// most of the time); its false answer throws CancelledError.
HandleResult remove_short_handles(TriangleMesh& mesh, const HandleParams& params = {}, const ProgressCallback& progress = {});

/// The same search without changing the mesh (params.remove is ignored).
HandleResult find_short_handles(const TriangleMesh& mesh, HandleParams params = {}, const ProgressCallback& progress = {});

}  // namespace pointsurf
