// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Signed distance from points to a triangle mesh, exact to the triangle: the deviation of a
// scan from the surface reconstructed from it, as Geomagic's and ImageWare's reports give it.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

class TriangleBvh;

/// How the sign of a distance is decided.
enum class DistanceSign {
  Auto,           // pseudo-normals on a manifold, consistently oriented mesh (open or closed)
                  // without self-intersections; the winding number on a nearly closed but
                  // imperfect one; unsigned (with a warning) otherwise
  PseudoNormal,   // angle-weighted pseudo-normal of the nearest feature (Baerentzen, Aanaes 2005)
  WindingNumber,  // negative where the generalized winding number exceeds 1/2 (inside)
  Unsigned,       // distances only, all >= 0
};

/// "auto", "pseudo-normal", "winding-number", "unsigned".
const EnumNames<DistanceSign>& distance_sign_names();

struct MeshDistanceParams {
  DistanceSign sign = DistanceSign::Auto;
  double max_distance = 0.0;       // cloud units; points farther get +-infinity; 0: no limit
  double max_crack_share = 0.01;   // Auto: the winding number is used when at most this share
                                   // of the edges are boundary edges (a crack, not an open surface)
  long known_self_intersections = -1;  // Auto: the mesh's count when already known (-1: counted here)
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<MeshDistanceParams>& fields();
  /// Throws UsageError naming the first value out of range (a negative max_distance).
  void validate() const;
};

struct MeshDistanceResult {
  std::vector<double> distances;   // N, cloud units; positive on the side the normals point to
                                   // (outside); closer to 0 is better
  std::vector<int> triangles;      // N, index of the nearest triangle (-1: none within max_distance)
  DistanceSign sign_used = DistanceSign::Unsigned;  // what Auto resolved to
  std::size_t self_intersections = 0;  // counted when Auto had to decide (closed manifold meshes)
  std::vector<std::string> warnings;   // e.g. why the distances are unsigned
};

/// Checks that `mesh` can be measured against: at least one triangle, indices in range, finite
/// vertices. Throws InputError "WHAT: ..." (WHAT names the mesh in the message, e.g. a file).
void check_measurable_mesh(const TriangleMesh& mesh, const std::string& what);

/// Signed distance from each point to `mesh` (exact closest point on the triangles, in double
/// precision about the mesh's centre). `bvh` may be a hierarchy over `mesh` already built, and
/// `topology` its analyze_topology() (the automatic sign needs it), so a caller that has them
/// does not pay for them twice. Throws InputError on an unmeasurable mesh (see
/// check_measurable_mesh) and when a point is not finite. Parallel (oneTBB); thread-safe.
/// O((N + F) log F).
MeshDistanceResult mesh_distances(std::span<const Vector3d> points, const TriangleMesh& mesh, const MeshDistanceParams& params = {},
                                  const TriangleBvh* bvh = nullptr, const ProgressCallback& progress = {},
                                  const MeshTopology* topology = nullptr);

/// Angle-weighted pseudo-normals of a mesh: per vertex (the angle-weighted sum of the unit
/// normals of its faces) and per face (unit normals; zero for degenerate faces). An edge's
/// pseudo-normal is the sum of the normals of its two faces: `across` holds, for edge i of
/// triangle t (from corner i to i+1), the other triangle on that edge at 3t + i (-1 on a boundary
/// or a non-manifold edge, where the face's own normal stands).
struct PseudoNormals {
  std::vector<Vector3d> vertex;  // V
  std::vector<Vector3d> face;    // F
  std::vector<int> across;       // 3F
  Vector3d edge(std::size_t t, int i) const {
    const int other = across[3 * t + static_cast<std::size_t>(i)];
    return other < 0 ? face[t] : Vector3d(face[t] + face[static_cast<std::size_t>(other)]);
  }
};
PseudoNormals pseudo_normals(const TriangleMesh& mesh);

}  // namespace pointsurf
