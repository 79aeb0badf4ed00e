// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Closing the small holes of a triangle mesh with triangles of its own vertices: the hole filler
// of every reconstruction, usable on any edge-manifold, consistently oriented mesh.
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

struct HoleFillParams {
  double max_perimeter_in_spacings = 20.0;  // >= 0: a hole (boundary loop of at most 64 corners)
                                            // is closed when its perimeter is at most this many
                                            // local spacings (the mean length of the mesh edges at
                                            // its corners); 0: none closed
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<HoleFillParams>& fields();
  /// Throws UsageError naming the value when it is negative or not finite.
  void validate() const;
};

struct HoleFillStats {
  std::size_t holes_before = 0;      // boundary loops of the input
  std::size_t holes_filled = 0;      // loops closed (a loop reopened and closed again counts each time)
  std::size_t triangles_added = 0;
  std::size_t triangles_removed = 0; // at pinched vertices (fans touching at a vertex) and folds,
                                     // removed so that the larger hole they open can be closed
  std::size_t holes_after = 0;       // boundary loops left (the larger ones, and those through a
                                     // non-manifold edge)
  bool face_fields_dropped = false;  // the input's face fields were dropped (triangles changed)
};

/// Closes the small holes of `mesh` in place: each boundary loop whose perimeter is at most
/// `max_perimeter_in_spacings` local spacings gets the triangulation of its corners (dynamic
/// programming over the loop; Barequet and Sharir 1995, Liepa 2003) whose new edges are not in
/// the mesh yet and whose triangles face the way their corners' normals do, with the smallest
/// worst normal deviation, then the smallest area. Loops through a pinched vertex are split
/// there; then up to 3 times the minor fans at pinched vertices and the triangles along small
/// holes that had no valid filling are removed and the holes this opens (up to 3x the limit)
/// closed again. No vertex is added or moved; vertex attributes are kept. Face fields of the
/// input are dropped when triangles are added or removed (a new triangle has no value).
/// Corner normals: `mesh.vertices.normals` when present, else the area-weighted face normals.
/// Loops through a non-manifold or inconsistently oriented edge are left open.
/// Throws UsageError for a parameter out of range, InputError for an invalid mesh (indices out of
/// range, attribute sizes). Cost: about linear in the mesh size plus m^3 per hole of m corners.
HoleFillStats fill_holes(TriangleMesh& mesh, const HoleFillParams& params = {});

}  // namespace pointsurf
