// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/evaluate/surface_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/triangle_bvh.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

std::vector<Vector3d> sample_mesh_surface(std::span<const Vector3d> vertices, std::span<const Triangle> triangles, std::size_t n,
                                          std::uint64_t seed, std::vector<std::uint32_t>* triangle_of) {
  if (triangle_of != nullptr) triangle_of->clear();
  std::vector<double> cumulative(triangles.size());
  double total = 0.0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vector3d& a = vertices[static_cast<std::size_t>(triangles[t][0])];
    total += 0.5 * (vertices[static_cast<std::size_t>(triangles[t][1])] - a).cross(vertices[static_cast<std::size_t>(triangles[t][2])] - a).norm();
    cumulative[t] = total;
  }
  std::vector<Vector3d> samples;
  if (triangles.empty() || !(total > 0.0)) return samples;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  samples.reserve(n);
  if (triangle_of != nullptr) triangle_of->reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double pick = uniform(rng) * total;
    const std::size_t t =
        std::min<std::size_t>(triangles.size() - 1, static_cast<std::size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin()));
    double u = uniform(rng), v = uniform(rng);
    if (u + v > 1.0) {
      u = 1.0 - u;
      v = 1.0 - v;
    }
    const Vector3d& a = vertices[static_cast<std::size_t>(triangles[t][0])];
    samples.push_back(a + u * (vertices[static_cast<std::size_t>(triangles[t][1])] - a) + v * (vertices[static_cast<std::size_t>(triangles[t][2])] - a));
    if (triangle_of != nullptr) triangle_of->push_back(static_cast<std::uint32_t>(t));
  }
  return samples;
}

std::vector<Vector3d> sample_mesh_surface(const TriangleMesh& mesh, std::size_t n, std::uint64_t seed) {
  return sample_mesh_surface(mesh.vertices.positions, mesh.triangles, n, seed);
}

std::vector<double> nearest_surface_distances(std::span<const Vector3d> points, const SurfaceView& to, bool exact, std::size_t samples,
                                              std::uint64_t seed, const TriangleBvh* bvh, const KdTree* tree_over_points) {
  std::vector<double> out(points.size(), 0.0);
  const std::vector<std::uint32_t> order = points.size() > 10000 ? morton_order(points) : std::vector<std::uint32_t>{};
  if (to.is_mesh() && exact) {
    std::optional<TriangleBvh> own;
    if (bvh == nullptr) bvh = &own.emplace(to.points, to.triangles);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      int previous = -1;
      for (std::size_t k = r.begin(); k != r.end(); ++k) {
        const std::size_t i = order.empty() ? k : order[k];
        const ClosestPoint c = bvh->closest_near(points[i], previous);
        previous = c.triangle;
        out[i] = std::sqrt(c.squared_distance);
      }
    });
    return out;
  }
  std::vector<Vector3d> sampled;
  std::span<const Vector3d> targets = to.points;
  if (to.is_mesh() && samples > 0) {
    sampled = sample_mesh_surface(to.points, to.triangles, samples, seed);
    targets = sampled;
  }
  if (targets.empty()) throw InputError("the surface measured to has no points");
  std::optional<KdTree> own_tree;
  const KdTree& tree = tree_over_points != nullptr && sampled.empty() ? *tree_over_points : own_tree.emplace(targets);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor> nn;
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::size_t i = order.empty() ? k : order[k];
      tree.knn(points[i], 1, nn);
      out[i] = std::sqrt(nn.front().squared_distance);
    }
  });
  return out;
}

std::vector<double> vertex_deviation_from_points(const TriangleMesh& mesh, std::span<const Vector3d> points, std::span<const double> deviations,
                                                 const TriangleBvh* bvh) {
  if (points.size() != deviations.size())
    throw InputError(fmt::format("vertex_deviation_from_points: {} deviations for {} points", deviations.size(), points.size()));
  const std::size_t nv = mesh.vertices.positions.size();
  std::vector<double> out(nv, std::numeric_limits<double>::quiet_NaN());
  if (mesh.triangles.empty() || points.empty()) return out;
  std::optional<TriangleBvh> own;
  if (bvh == nullptr) bvh = &own.emplace(mesh);
  std::vector<int> triangle(points.size(), -1);
  const std::vector<std::uint32_t> order = points.size() > 10000 ? morton_order(points) : std::vector<std::uint32_t>{};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    std::optional<Vector3d> previous;
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::size_t i = order.empty() ? k : order[k];
      if (!std::isfinite(deviations[i]) || !points[i].allFinite()) continue;
      const ClosestPoint c = bvh->closest_near(points[i], previous);
      previous = c.point;
      triangle[i] = c.triangle;
    }
  });
  // Sums per vertex, in point order (the same result on every run).
  std::vector<double> sum(nv, 0.0), sum_sq(nv, 0.0);
  std::vector<std::uint32_t> count(nv, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (triangle[i] < 0) continue;
    for (int c = 0; c < 3; ++c) {
      const std::size_t v = static_cast<std::size_t>(mesh.triangles[static_cast<std::size_t>(triangle[i])][c]);
      sum[v] += deviations[i];
      sum_sq[v] += deviations[i] * deviations[i];
      ++count[v];
    }
  }
  for (std::size_t v = 0; v < nv; ++v)
    if (count[v] > 0) out[v] = (sum[v] < 0.0 ? -1.0 : 1.0) * std::sqrt(sum_sq[v] / static_cast<double>(count[v]));
  return out;
}

namespace {

OneSidedDistance one_sided(const std::vector<double>& d) {
  OneSidedDistance s;
  s.count = d.size();
  double sum = 0.0, sq = 0.0;
  for (double v : d) {
    sum += v;
    sq += v * v;
    s.max = std::max(s.max, v);
  }
  if (!d.empty()) {
    s.mean = sum / static_cast<double>(d.size());
    s.rms = std::sqrt(sq / static_cast<double>(d.size()));
  }
  return s;
}

}  // namespace

const FieldTable<SurfaceDistanceParams>& SurfaceDistanceParams::fields() {
  static const FieldTable<SurfaceDistanceParams> table = [] {
    using P = SurfaceDistanceParams;
    FieldTable<P> t;
    t.boolean("exact", &P::exact, "Distances to a mesh are point-to-triangle; false: to its samples").internal();
    t.integer("samples", &P::samples, "Points sampled area-uniformly on a mesh that distances are measured from; 0: its vertices")
        .range(0, 1e9)
        .unit("points");
    t.integer("seed", &P::seed, "Seed of the sampling");
    return t;
  }();
  return table;
}

void SurfaceDistanceParams::validate() const { fields().validate(*this, "surface_distance"); }

SurfaceDistanceResult surface_distance(const SurfaceView& a, const SurfaceView& b, const SurfaceDistanceParams& params) {
  params.validate();
  if (a.points.empty() || b.points.empty()) throw InputError(fmt::format("surface {} has no points", a.points.empty() ? "a" : "b"));
  for (const SurfaceView* s : {&a, &b})
    for (std::size_t i = 0; i < s->points.size(); ++i)
      if (!s->points[i].allFinite()) throw InputError(fmt::format("surface {}: point {} is not finite", s == &a ? "a" : "b", i));
  SurfaceDistanceResult r;
  auto from_points = [&](const SurfaceView& s, std::vector<Vector3d>& storage, std::size_t& sampled) -> std::span<const Vector3d> {
    if (!s.is_mesh() || params.samples == 0) return s.points;
    storage = sample_mesh_surface(s.points, s.triangles, params.samples, params.seed);
    sampled = storage.size();
    return storage;
  };
  std::vector<Vector3d> sa, sb;
  const std::span<const Vector3d> pa = from_points(a, sa, r.samples_a), pb = from_points(b, sb, r.samples_b);
  r.a_to_b = one_sided(nearest_surface_distances(pa, b, params.exact, params.samples, params.seed + 1));
  r.b_to_a = one_sided(nearest_surface_distances(pb, a, params.exact, params.samples, params.seed + 2));
  r.chamfer = 0.5 * (r.a_to_b.mean + r.b_to_a.mean);
  r.hausdorff = std::max(r.a_to_b.max, r.b_to_a.max);
  return r;
}

}  // namespace pointsurf
