// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/evaluate/mesh_distance.h"

#include <atomic>
#include <cmath>
#include <limits>
#include <cstdint>
#include <mutex>
#include <optional>
#include <utility>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/mesh_quality.h"
#include "pointsurf/evaluate/triangle_bvh.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

const EnumNames<DistanceSign>& distance_sign_names() {
  static const EnumNames<DistanceSign> names{{{DistanceSign::Auto, "auto"},
                                              {DistanceSign::PseudoNormal, "pseudo-normal"},
                                              {DistanceSign::WindingNumber, "winding-number"},
                                              {DistanceSign::Unsigned, "unsigned"}}};
  return names;
}

const FieldTable<MeshDistanceParams>& MeshDistanceParams::fields() {
  static const FieldTable<MeshDistanceParams> table = [] {
    using P = MeshDistanceParams;
    FieldTable<P> t;
    t.choice("sign", &P::sign, distance_sign_names(), "How the side is decided: auto picks pseudo-normals, the winding number, or unsigned");
    t.number("max_distance", &P::max_distance, "Points farther are left out of the statistics; 0: no limit").unit("cloud units").non_negative();
    t.number("max_crack_share", &P::max_crack_share, "Auto: the winding number is used when at most this share of the edges are boundary edges")
        .range(0.0, 1.0)
        .internal();
    t.integer("known_self_intersections", &P::known_self_intersections, "Auto: the mesh's self-intersection count when known; -1: counted")
        .at_least(-1)
        .internal();
    return t;
  }();
  return table;
}

void MeshDistanceParams::validate() const { fields().validate(*this, "mesh_distances"); }

void check_measurable_mesh(const TriangleMesh& mesh, const std::string& what) {
  if (mesh.triangles.empty())
    throw InputError(fmt::format("{}: the mesh has no faces ({} vertices); a distance needs triangles", what, mesh.vertices.positions.size()));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const int v = mesh.triangles[t][c];
      if (v < 0 || static_cast<std::size_t>(v) >= mesh.vertices.positions.size())
        throw InputError(fmt::format("{}: triangle {}: vertex index {} out of range (the mesh has {} vertices)", what, t, v,
                                     mesh.vertices.positions.size()));
      if (!mesh.vertices.positions[static_cast<std::size_t>(v)].allFinite())
        throw InputError(fmt::format("{}: vertex {} (of triangle {}) is not finite", what, v, t));
    }
}

PseudoNormals pseudo_normals(const TriangleMesh& mesh) {
  const std::size_t f = mesh.triangles.size();
  PseudoNormals n;
  n.vertex.assign(mesh.vertices.positions.size(), Vector3d::Zero());
  n.across.assign(3 * f, -1);
  n.face.assign(f, Vector3d::Zero());
  // Undirected edges as (smaller, larger) keys with their use 3t + i, sorted so that the uses of
  // one edge lie together.
  std::vector<std::pair<std::uint64_t, std::size_t>> edges;
  edges.reserve(3 * f);
  for (std::size_t t = 0; t < f; ++t) {
    const Triangle& tri = mesh.triangles[t];
    const Vector3d& a = mesh.vertices.positions[static_cast<std::size_t>(tri[0])];
    const Vector3d cross = (mesh.vertices.positions[static_cast<std::size_t>(tri[1])] - a).cross(mesh.vertices.positions[static_cast<std::size_t>(tri[2])] - a);
    const double len = cross.norm();
    if (len > 0.0) n.face[t] = cross / len;
    for (int i = 0; i < 3; ++i) {
      const int u = tri[i], v = tri[(i + 1) % 3];
      const auto lo = static_cast<std::uint64_t>(std::min(u, v)), hi = static_cast<std::uint64_t>(std::max(u, v));
      edges.emplace_back((lo << 32) | hi, 3 * t + std::size_t(i));
      // The angle of the corner at vertex tri[i].
      const Vector3d e1 = mesh.vertices.positions[static_cast<std::size_t>(tri[(i + 1) % 3])] - mesh.vertices.positions[static_cast<std::size_t>(tri[i])];
      const Vector3d e2 = mesh.vertices.positions[static_cast<std::size_t>(tri[(i + 2) % 3])] - mesh.vertices.positions[static_cast<std::size_t>(tri[i])];
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      n.vertex[static_cast<std::size_t>(tri[i])] += angle * n.face[t];
    }
  }
  tbb::parallel_sort(edges.begin(), edges.end());
  for (std::size_t b = 0; b < edges.size();) {
    std::size_t e = b;
    while (e < edges.size() && edges[e].first == edges[b].first) ++e;
    if (e - b == 2) {  // a manifold edge: each side sees the other
      n.across[edges[b].second] = static_cast<int>(edges[b + 1].second / 3);
      n.across[edges[b + 1].second] = static_cast<int>(edges[b].second / 3);
    }
    b = e;
  }
  return n;
}

MeshDistanceResult mesh_distances(std::span<const Vector3d> points, const TriangleMesh& mesh, const MeshDistanceParams& params,
                                  const TriangleBvh* bvh, const ProgressCallback& progress, const MeshTopology* topology) {
  check_measurable_mesh(mesh, "mesh");
  params.validate();
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite()) throw InputError(fmt::format("point {} is not finite", i));
  std::optional<TriangleBvh> own;
  if (bvh == nullptr) bvh = &own.emplace(mesh);

  MeshDistanceResult result;
  DistanceSign sign = params.sign;
  if (sign == DistanceSign::Auto) {
    std::optional<MeshTopology> own_topology;
    const MeshTopology& topo = topology != nullptr ? *topology : own_topology.emplace(analyze_topology(mesh));
    const bool manifold = topo.edge_manifold() && topo.non_manifold_vertices == 0 && topo.oriented();
    bool intersecting = false;
    if (manifold && topo.closed()) {
      result.self_intersections = params.known_self_intersections >= 0 ? static_cast<std::size_t>(params.known_self_intersections)
                                                                       : count_self_intersections(mesh, *bvh);
      intersecting = result.self_intersections > 0;
    }
    const bool nearly_closed =
        topo.oriented() && static_cast<double>(topo.boundary_edges) <= params.max_crack_share * static_cast<double>(std::max<std::size_t>(1, topo.edges));
    if (manifold && !intersecting) sign = DistanceSign::PseudoNormal;
    else if (nearly_closed) sign = DistanceSign::WindingNumber;
    else {
      sign = DistanceSign::Unsigned;
      result.warnings.push_back(fmt::format("distances are unsigned: the mesh is {} ({} non-manifold edges, {} inconsistently oriented, {} "
                                            "boundary edges of {})",
                                            topo.oriented() ? "open and not manifold" : "not consistently oriented", topo.non_manifold_edges,
                                            topo.inconsistent_edges, topo.boundary_edges, topo.edges));
    }
    if (sign == DistanceSign::WindingNumber)
      result.warnings.push_back(fmt::format("sign from the winding number: the mesh is {}",
                                            intersecting ? fmt::format("self-intersecting ({} pairs)", result.self_intersections)
                                                         : std::string("closed but not a clean manifold")));
  }
  result.sign_used = sign;
  std::optional<PseudoNormals> normals;
  if (sign == DistanceSign::PseudoNormal) normals = pseudo_normals(mesh);

  const std::size_t n = points.size();
  result.distances.assign(n, 0.0);
  result.triangles.assign(n, -1);
  const double limit = params.max_distance > 0.0 ? params.max_distance : std::numeric_limits<double>::infinity();
  std::atomic<std::size_t> done{0};
  std::atomic<bool> cancelled{false};
  std::mutex progress_lock;
  // Queries in Morton order: neighbours walk the same nodes, which stay in cache.
  const std::vector<std::uint32_t> order = n > 10000 ? morton_order(points) : std::vector<std::uint32_t>{};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
    if (cancelled.load(std::memory_order_relaxed)) return;
    // Each query starts from the previous one's closest triangle (Morton order: a near one).
    int previous = -1;
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const std::size_t i = order.empty() ? k : order[k];
      const ClosestPoint c = bvh->closest_near(points[i], previous, limit);
      if (c.found()) previous = c.triangle;
      if (!c.found()) {
        result.distances[i] = std::numeric_limits<double>::infinity();
        continue;
      }
      result.triangles[i] = c.triangle;
      const double d = std::sqrt(c.squared_distance);
      double s = 1.0;
      if (sign == DistanceSign::PseudoNormal && d > 0.0) {
        const std::size_t t = static_cast<std::size_t>(c.triangle);
        const Vector3d pn = c.feature == TriangleFeature::Face   ? normals->face[t]
                            : c.feature == TriangleFeature::Edge ? normals->edge(t, c.local_index)
                                                                 : normals->vertex[static_cast<std::size_t>(mesh.triangles[t][c.local_index])];
        // Both vectors about the nearest point: p - c is computed from absolute coordinates
        // whose difference is exact to the rounding of the inputs.
        s = (points[i] - c.point).dot(pn) < 0.0 ? -1.0 : 1.0;
      } else if (sign == DistanceSign::WindingNumber && d > 0.0) {
        s = bvh->winding_number(points[i]) > 0.5 ? -1.0 : 1.0;
      }
      result.distances[i] = s * d;
    }
    done.fetch_add(range.size());
    // The callback is never called from two threads at once (core/progress.h); the count is
    // read under the lock, so successive reports never go backwards.
    if (progress && progress_lock.try_lock()) {
      if (!progress(static_cast<double>(done.load()) / static_cast<double>(n))) cancelled = true;
      progress_lock.unlock();
    }
  });
  if (cancelled) throw CancelledError();
  return result;
}

}  // namespace pointsurf
