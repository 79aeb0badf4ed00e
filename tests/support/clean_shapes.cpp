// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/clean_shapes.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace pointsurf::test {

std::vector<std::uint32_t> add_drift_outliers(PointCloud& cloud, std::size_t count, double min_height, double max_height,
                                              std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, cloud.size() - 1);
  std::uniform_real_distribution<double> height(min_height, max_height);
  PointCloud extra;
  std::vector<std::uint32_t> indices;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = pick(rng);
    const Vector3d n = cloud.normals[j].normalized();
    extra.positions.push_back(cloud.positions[j] + height(rng) * n);
    extra.normals.push_back(n);
    indices.push_back(static_cast<std::uint32_t>(cloud.size() + i));
  }
  cloud.append(extra);
  return indices;
}

std::vector<std::uint32_t> add_scattered_outliers(PointCloud& cloud, std::size_t count, double margin, double min_distance,
                                                  const std::function<double(const Vector3d&)>& distance_to_surface,
                                                  std::uint64_t seed) {
  BoundingBox box = bounding_box(cloud.positions);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vector3d low = box.min - Vector3d::Constant(margin), size = box.extent() + Vector3d::Constant(2.0 * margin);
  PointCloud extra;
  std::vector<std::uint32_t> indices;
  while (extra.size() < count) {
    const Vector3d p = low + Vector3d(u(rng) * size.x(), u(rng) * size.y(), u(rng) * size.z());
    if (distance_to_surface(p) < min_distance) continue;
    indices.push_back(static_cast<std::uint32_t>(cloud.size() + extra.size()));
    extra.positions.push_back(p);
    if (cloud.has_normals()) extra.normals.push_back(Vector3d::UnitZ());
  }
  cloud.append(extra);
  return indices;
}

double distance_to_sphere(const Vector3d& p, double radius, const Vector3d& center) { return std::abs((p - center).norm() - radius); }

double distance_to_cube(const Vector3d& p, double half) {
  const Vector3d a = p.cwiseAbs() - Vector3d::Constant(half);
  if ((a.array() <= 0.0).all()) return -a.maxCoeff();  // inside: to the nearest face
  return a.cwiseMax(0.0).norm();
}

double distance_to_cube_edge(const Vector3d& p, double half) {
  const Vector3d a = p.cwiseAbs() - Vector3d::Constant(half);
  double best = INFINITY;
  for (int axis = 0; axis < 3; ++axis) {
    // The edges parallel to `axis`: the other two coordinates at +-half.
    const double along = std::max(a[axis], 0.0);
    const double u = a[(axis + 1) % 3], v = a[(axis + 2) % 3];
    best = std::min(best, std::sqrt(u * u + v * v + along * along));
  }
  return best;
}

double rms_distance(const std::vector<Vector3d>& points, const std::function<double(const Vector3d&)>& distance,
                    const std::vector<bool>& select) {
  double squares = 0.0;
  std::size_t used = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!select.empty() && !select[i]) continue;
    const double d = distance(points[i]);
    squares += d * d;
    ++used;
  }
  return used == 0 ? 0.0 : std::sqrt(squares / double(used));
}

Detection score_removal(const std::vector<std::uint32_t>& kept, std::size_t n, const std::vector<std::uint32_t>& outliers) {
  std::vector<bool> is_kept(n, false), is_outlier(n, false);
  for (std::uint32_t i : kept) is_kept[i] = true;
  for (std::uint32_t i : outliers) is_outlier[i] = true;
  std::size_t removed = 0, true_removed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (is_kept[i]) continue;
    ++removed;
    true_removed += is_outlier[i];
  }
  Detection d;
  d.precision = removed == 0 ? 1.0 : double(true_removed) / double(removed);
  d.recall = outliers.empty() ? 1.0 : double(true_removed) / double(outliers.size());
  return d;
}

}  // namespace pointsurf::test
