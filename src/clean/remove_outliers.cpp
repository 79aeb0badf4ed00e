// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/clean/remove_outliers.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "clean/detail/clean_common.h"
#include "normals/detail/progress_reporter.h"
#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

constexpr std::size_t kGrain = 256;
// RANSAC: the smallest sine of the angle at the first sample between the other two.
constexpr double kMinSine = 0.1;

// Runs `visit(i, buffer)` for every point in the tree's spatial order, in parallel, with a
// thread-local neighbour buffer and progress over [0, 1).
template <typename Visit>
void for_each_point(const KdTree& tree, detail::ProgressReporter& reporter, Visit&& visit) {
  const std::span<const std::uint32_t> order = tree.spatial_order();
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    if (reporter.cancelled()) return;
    std::vector<Neighbor>& buffer = buffers.local();
    for (std::size_t pos = r.begin(); pos != r.end(); ++pos) visit(order[pos], buffer);
    reporter.advance(r.size());
  });
  reporter.throw_if_cancelled();
}

OutlierResult collect(const std::vector<std::uint8_t>& keep, double threshold) {
  OutlierResult result;
  result.threshold = threshold;
  result.kept.reserve(keep.size());
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i] != 0) result.kept.push_back(static_cast<std::uint32_t>(i));
  result.removed = keep.size() - result.kept.size();
  return result;
}

// SplitMix64: a small, good mixer for per-point seeds.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

OutlierResult remove_statistical_outliers(const PointCloud& cloud, const StatisticalOutlierParams& params, const KdTree* tree,
                                          const ProgressCallback& progress) {
  constexpr std::string_view fn = "remove_statistical_outliers";
  if (params.k < 1) throw UsageError(fmt::format("{}: k must be >= 1, got {}", fn, params.k));
  detail::check_positive(fn, "std_ratio", params.std_ratio);
  detail::check_cloud(fn, cloud, 2, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const std::size_t n = cloud.size(), k = static_cast<std::size_t>(params.k);

  std::vector<double> mean_distance(n);
  detail::ProgressReporter reporter(progress, 0.0, 1.0, n);
  for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
    t.knn(cloud.positions[i], k, neighbors);
    double sum = 0.0;
    for (const Neighbor& nb : neighbors) sum += std::sqrt(nb.squared_distance);
    mean_distance[i] = sum / double(neighbors.size());
  });
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return statistical_outliers_from_distances(mean_distance, params.std_ratio);
}

OutlierResult statistical_outliers_from_distances(std::span<const double> mean_distances, double std_ratio) {
  constexpr std::string_view fn = "statistical_outliers_from_distances";
  detail::check_positive(fn, "std_ratio", std_ratio);
  const std::size_t n = mean_distances.size();
  if (n < 2) throw UsageError(fmt::format("{}: needs at least 2 distances, got {}", fn, n));
  // Serial sums in index order, as Open3D does them, so that a point at the threshold is
  // decided the same way. Zero mean distances count in N but not in the squared deviations.
  double sum = 0.0;
  for (double d : mean_distances) sum += d;
  const double mean = sum / double(n);
  double squares = 0.0;
  for (double d : mean_distances)
    if (d > 0.0) squares += (d - mean) * (d - mean);
  const double threshold = mean + std_ratio * std::sqrt(squares / double(n - 1));
  std::vector<std::uint8_t> keep(n);
  for (std::size_t i = 0; i < n; ++i) keep[i] = mean_distances[i] > 0.0 && mean_distances[i] < threshold;
  return collect(keep, threshold);
}

OutlierResult remove_radius_outliers(const PointCloud& cloud, const RadiusOutlierParams& params, const KdTree* tree,
                                     const ProgressCallback& progress) {
  constexpr std::string_view fn = "remove_radius_outliers";
  if (params.min_neighbours < 1) throw UsageError(fmt::format("{}: min_neighbours must be >= 1, got {}", fn, params.min_neighbours));
  detail::check_length(fn, "radius", params.radius, false);
  if (params.radius == 0.0) detail::check_positive(fn, "radius_in_spacings", params.radius_in_spacings);
  detail::check_cloud(fn, cloud, 2, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const double radius = detail::resolve_length(params.radius, params.radius_in_spacings, t);
  // The point itself is among the results; counting stops once it has min_neighbours others.
  const std::size_t wanted = static_cast<std::size_t>(params.min_neighbours) + 1;

  std::vector<std::uint8_t> keep(cloud.size());
  detail::ProgressReporter reporter(progress, 0.0, 1.0, cloud.size());
  for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
    t.hybrid(cloud.positions[i], wanted, radius, neighbors);
    keep[i] = neighbors.size() >= wanted;
  });
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return collect(keep, radius);
}

OutlierResult remove_ransac_outliers(const PointCloud& cloud, const RansacOutlierParams& params, const KdTree* tree,
                                     const ProgressCallback& progress) {
  constexpr std::string_view fn = "remove_ransac_outliers";
  if (params.k < 4) throw UsageError(fmt::format("{}: k must be >= 4, got {}", fn, params.k));
  if (params.iterations < 1) throw UsageError(fmt::format("{}: iterations must be >= 1, got {}", fn, params.iterations));
  if (!(params.min_support > 0.0 && params.min_support <= 1.0))
    throw UsageError(fmt::format("{}: min_support must be in (0, 1], got {}", fn, params.min_support));
  detail::check_length(fn, "distance", params.distance, false);
  if (params.distance == 0.0) detail::check_positive(fn, "distance_in_spacings", params.distance_in_spacings);
  detail::check_cloud(fn, cloud, 4, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const double distance = detail::resolve_length(params.distance, params.distance_in_spacings, t);
  const std::size_t k = static_cast<std::size_t>(params.k);

  std::vector<std::uint8_t> keep(cloud.size());
  tbb::enumerable_thread_specific<std::vector<Eigen::Vector3d>> offset_buffers;
  detail::ProgressReporter reporter(progress, 0.0, 1.0, cloud.size());
  for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
    const Eigen::Vector3d& p = cloud.positions[i];
    t.knn(p, k, neighbors);
    // Offsets of the other points from this one: small numbers even for georeferenced clouds.
    // The point itself takes no part in the fits, so it cannot support a plane through itself.
    std::vector<Eigen::Vector3d>& q = offset_buffers.local();
    q.clear();
    for (const Neighbor& nb : neighbors)
      if (nb.index != i) q.push_back(t.point(nb.index) - p);
    const std::size_t m = q.size();
    if (m < 3) {
      keep[i] = 0;
      return;
    }
    const std::size_t support_needed = static_cast<std::size_t>(std::ceil(params.min_support * double(m) - 1e-9));
    std::uint64_t state = mix(params.seed ^ mix(std::bit_cast<std::uint64_t>(p.x()) ^
                                                mix(std::bit_cast<std::uint64_t>(p.y()) ^ mix(std::bit_cast<std::uint64_t>(p.z())))));
    bool fits = false;
    for (int it = 0; it < params.iterations && !fits; ++it) {
      std::size_t a = (state = mix(state)) % m, b = (state = mix(state)) % m, c = (state = mix(state)) % m;
      if (a == b || b == c || a == c) continue;
      const Eigen::Vector3d u = q[b] - q[a], v = q[c] - q[a];
      Eigen::Vector3d normal = u.cross(v);
      const double length = normal.norm();
      // Nearly collinear samples (angle below about 6 degrees) give no reliable plane.
      if (!(length > kMinSine * u.norm() * v.norm())) continue;
      normal /= length;
      const double offset = -normal.dot(q[a]);  // plane: normal . x + offset = 0; the point is x = 0
      if (std::abs(offset) > distance) continue;
      std::size_t support = 0;
      for (std::size_t j = 0; j < m && support < support_needed; ++j) support += std::abs(normal.dot(q[j]) + offset) <= distance;
      fits = support >= support_needed;
    }
    keep[i] = fits;
  });
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return collect(keep, distance);
}

PointCloud keep_points(const PointCloud& cloud, std::span<const std::uint32_t> kept) {
  std::vector<std::size_t> indices(kept.begin(), kept.end());
  for (std::size_t i : indices)
    if (i >= cloud.size()) throw UsageError(fmt::format("keep_points: index {} out of range for {} points", i, cloud.size()));
  return cloud.select(indices);
}

}  // namespace pointsurf
