// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/detail/lexicographic.h"
#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {
namespace {

// Distance from tree point i to its nearest distinct point, or -1 when every point coincides
// with it. Starts with k = 2 (the point itself and its nearest neighbour) and widens only
// when duplicates fill the list.
double nearest_distinct_distance(const KdTree& tree, std::size_t i, std::vector<Neighbor>& neighbors) {
  const std::size_t n = tree.size();
  for (std::size_t k = 2;; k = std::min(n, 4 * k)) {
    tree.knn(tree.point(i), k, neighbors);
    for (const Neighbor& nb : neighbors)
      if (nb.squared_distance > 0.0) return std::sqrt(nb.squared_distance);
    if (k >= n) return -1.0;
  }
}

// Indices of the points to average over: all of them, or a seeded sample without replacement
// (a partial Fisher-Yates shuffle), sorted so neighbouring queries stay near in memory.
std::vector<std::uint32_t> sample_indices(std::size_t n, std::size_t max_samples, std::uint64_t seed) {
  std::vector<std::uint32_t> indices(n);
  std::iota(indices.begin(), indices.end(), 0u);
  if (n <= max_samples) return indices;
  std::mt19937_64 rng(seed);
  for (std::size_t i = 0; i < max_samples; ++i) {
    std::uniform_int_distribution<std::size_t> pick(i, n - 1);
    std::swap(indices[i], indices[pick(rng)]);
  }
  indices.resize(max_samples);
  std::sort(indices.begin(), indices.end());
  return indices;
}

}  // namespace

double mean_spacing(const KdTree& tree, std::size_t max_samples, std::uint64_t seed) {
  const std::size_t n = tree.size();
  if (n < 2) throw UsageError(fmt::format("mean_spacing: needs at least 2 points, got {}", n));
  if (max_samples < 1) throw UsageError("mean_spacing: max_samples must be >= 1, got 0");
  const std::vector<std::uint32_t> samples = sample_indices(n, max_samples, seed);

  // Samples at one position share one answer: a stack of m copies costs one widening query,
  // not m of them (each would have to step over the whole stack).
  std::vector<std::uint32_t> by_position(samples.size()), first(samples.size());
  std::iota(by_position.begin(), by_position.end(), 0u);
  std::sort(by_position.begin(), by_position.end(), [&](std::uint32_t a, std::uint32_t b) {
    const Eigen::Vector3d &p = tree.point(samples[a]), &q = tree.point(samples[b]);
    return detail::lexicographic_less(p, q) || (p == q && a < b);
  });
  for (std::size_t q = 0; q < by_position.size(); ++q) {
    const std::uint32_t s = by_position[q];
    const bool same = q > 0 && tree.point(samples[s]) == tree.point(samples[by_position[q - 1]]);
    first[s] = same ? first[by_position[q - 1]] : s;
  }
  std::vector<double> distances(samples.size());
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 512), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor>& neighbors = buffers.local();
    for (std::size_t s = r.begin(); s != r.end(); ++s)
      if (first[s] == s) distances[s] = nearest_distinct_distance(tree, samples[s], neighbors);
  });
  for (std::size_t s = 0; s < samples.size(); ++s) distances[s] = distances[first[s]];
  // Summed serially in sample order so the result does not depend on the thread schedule.
  double sum = 0.0;
  std::size_t count = 0;
  for (double d : distances) {
    if (d < 0.0) continue;
    sum += d;
    ++count;
  }
  return count == 0 ? 0.0 : sum / double(count);
}

double mean_spacing(std::span<const Eigen::Vector3d> points, std::size_t max_samples, std::uint64_t seed) {
  if (points.size() < 2) throw UsageError(fmt::format("mean_spacing: needs at least 2 points, got {}", points.size()));
  const KdTree tree(points);
  return mean_spacing(tree, max_samples, seed);
}

}  // namespace pointsurf
