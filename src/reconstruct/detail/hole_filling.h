// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The hole filler shared by the three reconstructions and fill_holes() (reconstruct/
// fill_holes.h): small boundary loops closed by dynamic programming over the loop (Liepa 2003),
// pinched vertices and folds opened and the larger holes they leave closed again.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/triangle_mesh.h"
#include "pointsurf/reconstruct/fill_holes.h"
#include "reconstruct/detail/triangulate_half_edges.h"

namespace pointsurf::detail {

// The selected triangles and their unit normals, with the half-edge map they fill.
struct Selection {
  std::vector<Triangle> triangles;
  std::vector<Vector3d> normals;
  HalfEdgeMap edges;
  explicit Selection(std::size_t expected) : edges(3 * expected) {}
  /// With the spatial rank of each vertex (see HalfEdgeMap); `vertex_rank` must outlive it.
  Selection(std::size_t expected, const std::vector<std::uint32_t>* vertex_rank) : edges(3 * expected, vertex_rank) {}

  bool free_edges(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
    return !edges.contains(a, b) && !edges.contains(b, c) && !edges.contains(c, a);
  }
  void add(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vector3d& normal) {
    const auto t = static_cast<std::uint32_t>(triangles.size());
    triangles.emplace_back(int(a), int(b), int(c));
    normals.push_back(normal);
    edges.insert(a, b, t);
    edges.insert(b, c, t);
    edges.insert(c, a, t);
  }
  /// Removes the triangles flagged in `removed` (one per triangle), keeping the order of the
  /// others; new_id[t] is the new index of a kept triangle t. Linear, without re-hashing the kept
  /// edges.
  void remove(const std::vector<std::uint8_t>& removed, std::vector<std::uint32_t>& new_id) {
    const std::size_t f = triangles.size();
    new_id.assign(f, HalfEdgeMap::kNone);
    std::size_t kept = 0;
    for (std::size_t t = 0; t < f; ++t) {
      const Triangle& tri = triangles[t];
      if (removed[t]) {
        for (int c = 0; c < 3; ++c) edges.erase(std::uint32_t(tri[c]), std::uint32_t(tri[(c + 1) % 3]), std::uint32_t(t));
        continue;
      }
      new_id[t] = static_cast<std::uint32_t>(kept);
      triangles[kept] = tri;
      normals[kept] = normals[t];
      ++kept;
    }
    triangles.resize(kept);
    normals.resize(kept);
    edges.renumber(new_id);
  }
};

/// A hole half-edge y -> x: opposite to the boundary edge x -> y of `triangle`, which has no twin.
struct HoleEdge {
  std::uint32_t y, triangle, x;
};

/// The hole half-edges of `sel`, by y, then by triangle (the order in which a scan of all
/// triangles meets them). Scans the triangles in parallel; the map is only read.
std::vector<HoleEdge> all_hole_edges(const Selection& sel);

/// What close_holes did.
struct HoleClosing {
  std::size_t holes_filled = 0;     // loops closed (a loop reopened and closed again counts each time)
  std::size_t fill_triangles = 0;   // triangles added
  std::size_t pinch_triangles_removed = 0;  // triangles removed at pinched vertices and folds
};

/// Closes the holes of `sel` with at most 64 corners whose perimeter is at most
/// `max_perimeter_in_spacings` times the mean `local_spacing` of their corners; then, up to 3
/// times, opens the minor fans at pinched vertices and the folds along small holes that had no
/// valid filling, and closes the holes this opens (up to 3x the limit). `normals`: one unit
/// normal per vertex (the side the triangles face). Vertices flagged in `blocked` (may be empty)
/// are never part of a filled loop. `on_round(r)` is called after each round (r = 0..3).
/// `limit_factor(loop)` (may be empty), asked only for a loop over its limit, returns a factor
/// for that loop's limit (1: none) and whether the loop, when it then has no valid filling, is
/// opened like one within the limit (else it is left as it is).
struct LoopLimit {
  double factor = 1.0;
  bool open_if_unfilled = false;
};
using LoopLimitFactor = std::function<LoopLimit(const std::vector<std::uint32_t>& loop)>;
void close_holes(const std::vector<Vector3d>& positions, const std::vector<Vector3d>& normals,
                 const std::vector<double>& local_spacing, double max_perimeter_in_spacings, Selection& sel,
                 const std::vector<std::uint8_t>& blocked, HoleClosing& counts, const std::function<void(int)>& on_round = {},
                 const LoopLimitFactor& limit_factor = {});

/// fill_holes() (reconstruct/fill_holes.h) without its two topology passes: holes_before and
/// holes_after stay 0, and it runs even where the mesh has no boundary loop (fill_holes() then
/// returns at once, leaving pinched vertices of a closed mesh alone). For callers that analyse
/// the mesh themselves before and after.
HoleFillStats fill_mesh_holes(TriangleMesh& mesh, const HoleFillParams& params);

}  // namespace pointsurf::detail
