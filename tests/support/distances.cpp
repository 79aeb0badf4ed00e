// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/distances.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include <Eigen/Geometry>

#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::test {

std::vector<double> nearest_distances(const std::vector<Vector3d>& from, const std::vector<Vector3d>& to) {
  std::vector<double> distances(from.size(), 0.0);
  if (to.empty()) return std::vector<double>(from.size(), INFINITY);
  const KdTree tree(to);
  const NeighborLists lists = tree.knn_all(from, 1);
  for (std::size_t i = 0; i < from.size(); ++i) distances[i] = std::sqrt(lists[i][0].squared_distance);
  return distances;
}

SetDistances set_distances(const std::vector<Vector3d>& a, const std::vector<Vector3d>& b) {
  const std::vector<double> ab = nearest_distances(a, b), ba = nearest_distances(b, a);
  SetDistances d;
  double sum_ab = 0.0, sum_ba = 0.0, sq_ab = 0.0;
  for (double v : ab) { sum_ab += v; sq_ab += v * v; d.hausdorff = std::max(d.hausdorff, v); }
  for (double v : ba) { sum_ba += v; d.hausdorff = std::max(d.hausdorff, v); }
  const double na = std::max<double>(1.0, static_cast<double>(ab.size())), nb = std::max<double>(1.0, static_cast<double>(ba.size()));
  d.chamfer = 0.5 * (sum_ab / na + sum_ba / nb);
  d.rms_ab = std::sqrt(sq_ab / na);
  return d;
}

std::vector<Vector3d> sample_mesh_surface(const std::vector<Vector3d>& vertices, const std::vector<Eigen::Vector3i>& triangles,
                                          std::size_t n, std::uint64_t seed) {
  std::vector<double> cumulative(triangles.size());
  double total = 0.0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vector3d& a = vertices[triangles[t][0]];
    total += 0.5 * (vertices[triangles[t][1]] - a).cross(vertices[triangles[t][2]] - a).norm();
    cumulative[t] = total;
  }
  std::vector<Vector3d> samples;
  if (triangles.empty() || total <= 0.0) return samples;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  samples.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double pick = uniform(rng) * total;
    const std::size_t t = std::min<std::size_t>(triangles.size() - 1, std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
    double u = uniform(rng), v = uniform(rng);
    if (u + v > 1.0) { u = 1.0 - u; v = 1.0 - v; }
    const Vector3d& a = vertices[triangles[t][0]];
    samples.push_back(a + u * (vertices[triangles[t][1]] - a) + v * (vertices[triangles[t][2]] - a));
  }
  return samples;
}

}  // namespace pointsurf::test
