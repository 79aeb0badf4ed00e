// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/reconstruct_surface.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::test {

std::vector<Vector3d> sample_triangles(const TriangleMesh& mesh, std::size_t n, std::uint64_t seed) {
  std::vector<double> cumulative(mesh.triangles.size());
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& f = mesh.triangles[t];
    const Vector3d& a = mesh.vertices[f[0]];
    const Vector3d ab = mesh.vertices[f[1]] - a, ac = mesh.vertices[f[2]] - a;
    total += 0.5 * ab.cross(ac).norm();
    cumulative[t] = total;
  }
  std::vector<Vector3d> samples;
  if (mesh.triangles.empty() || !(total > 0.0)) return samples;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  samples.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double pick = uniform(rng) * total;
    const auto t = std::min<std::size_t>(mesh.triangles.size() - 1,
                                         std::size_t(std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin()));
    double u = uniform(rng), v = uniform(rng);
    if (u + v > 1.0) { u = 1.0 - u; v = 1.0 - v; }
    const Triangle& f = mesh.triangles[t];
    const Vector3d& a = mesh.vertices[f[0]];
    samples.push_back(a + u * (mesh.vertices[f[1]] - a) + v * (mesh.vertices[f[2]] - a));
  }
  return samples;
}

double max_nearest_distance(const std::vector<Vector3d>& from, const std::vector<Vector3d>& to) {
  if (from.empty()) return 0.0;
  if (to.empty()) return INFINITY;
  const KdTree tree(to);
  const NeighborLists lists = tree.knn_all(from, 1);
  double worst = 0.0;
  for (std::size_t i = 0; i < from.size(); ++i) worst = std::max(worst, lists[i][0].squared_distance);
  return std::sqrt(worst);
}

}  // namespace pointsurf::test
