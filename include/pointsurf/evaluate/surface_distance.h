// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Distances between two surfaces given as clouds or meshes: Chamfer and Hausdorff, one-sided
// and symmetric, and the area-uniform mesh sampling they (and the benches and tests) use.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

/// `n` points drawn area-uniformly on the triangles of `mesh` (seeded, so repeatable).
/// Degenerate triangles get no samples; a mesh without area gives none. O(n log F).
/// `triangle_of`, when given, receives the triangle each sample lies on (same size).
std::vector<Vector3d> sample_mesh_surface(const TriangleMesh& mesh, std::size_t n, std::uint64_t seed = 3);
std::vector<Vector3d> sample_mesh_surface(std::span<const Vector3d> vertices, std::span<const Triangle> triangles, std::size_t n,
                                          std::uint64_t seed = 3, std::vector<std::uint32_t>* triangle_of = nullptr);

/// One surface: points, with triangles when it is a mesh.
struct SurfaceView {
  std::span<const Vector3d> points;       // a cloud's points or a mesh's vertices
  std::span<const Triangle> triangles;    // empty for a cloud
  bool is_mesh() const noexcept { return !triangles.empty(); }
};

struct SurfaceDistanceParams {
  bool exact = true;               // distances to a mesh are point-to-triangle; false: to its samples
  std::size_t samples = 100000;    // points sampled on a mesh that distances are measured from
                                   // (and to, when !exact); 0: its vertices
  std::uint64_t seed = 3;
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<SurfaceDistanceParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// Distances from the points of one surface to the other.
struct OneSidedDistance {
  std::size_t count = 0;           // points measured from
  double mean = 0.0, rms = 0.0, max = 0.0;  // cloud units; smaller is better
};

struct SurfaceDistanceResult {
  OneSidedDistance a_to_b, b_to_a;
  double chamfer = 0.0;            // mean of the two one-sided means (smaller is better)
  double hausdorff = 0.0;          // max of the two one-sided maxima (smaller is better)
  std::size_t samples_a = 0, samples_b = 0;  // points sampled on a mesh side (0 for a cloud)
};

class TriangleBvh;
class KdTree;

/// Nearest distances from `points` to `to` (exact to the triangle for a mesh when `exact`,
/// through `bvh` when it is a hierarchy over `to` already built; else through `samples` seeded
/// samples of it, or its vertices when samples is 0). A cloud `to` is searched through
/// `tree_over_points` when it is a kd-tree over to.points already built. Queries run in Morton
/// order. Parallel; thread-safe.
std::vector<double> nearest_surface_distances(std::span<const Vector3d> points, const SurfaceView& to, bool exact = true,
                                              std::size_t samples = 100000, std::uint64_t seed = 3, const TriangleBvh* bvh = nullptr,
                                              const KdTree* tree_over_points = nullptr);

/// Per vertex of `mesh`: the deviation of the measured points seen at the vertex, for colouring
/// the mesh. Each point of `points` is assigned to its closest triangle (through `bvh` when it
/// is a hierarchy over `mesh`), and its value `deviations[i]` to that triangle's three corners;
/// a vertex gets the signed RMS of its values (the root mean square, with the sign of their
/// mean), so a triangle that cuts a chord under the scan shows the scan's offset across it,
/// and noise beyond the tolerance shows as such instead of averaging to zero. Vertices no point
/// is assigned to get NaN (drawn grey: not measured). Non-finite deviations are skipped.
/// Throws InputError when the sizes differ. Parallel; thread-safe.
std::vector<double> vertex_deviation_from_points(const TriangleMesh& mesh, std::span<const Vector3d> points, std::span<const double> deviations,
                                                 const TriangleBvh* bvh = nullptr);

/// Chamfer and Hausdorff distances between `a` and `b`. Throws InputError when a side is empty.
SurfaceDistanceResult surface_distance(const SurfaceView& a, const SurfaceView& b, const SurfaceDistanceParams& params = {});

}  // namespace pointsurf
