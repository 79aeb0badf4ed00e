// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Checks and defaults shared by the cleaning functions.
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>
#include <string_view>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/detail/progress_reporter.h"

#include "pointsurf/core/error.h"
#include "pointsurf/core/length.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::detail {

/// Throws UsageError when the cloud has fewer than `min_points` points or `tree` was built
/// over another number of points.
inline void check_cloud(std::string_view function, const PointCloud& cloud, std::size_t min_points, const KdTree* tree) {
  if (cloud.size() < min_points)
    throw UsageError(fmt::format("{}: needs at least {} points, got {}", function, min_points, cloud.size()));
  if (cloud.size() > std::size_t(UINT32_MAX))
    throw UsageError(fmt::format("{}: {} points exceed the 2^32-1 point indices hold", function, cloud.size()));
  if (tree != nullptr && tree->size() != cloud.size())
    throw UsageError(fmt::format("{}: the kd-tree holds {} points but the cloud has {}", function, tree->size(), cloud.size()));
}

/// Throws UsageError unless `value` is finite and > 0.
inline void check_positive(std::string_view function, std::string_view name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) throw UsageError(fmt::format("{}: {} must be > 0, got {}", function, name, value));
}

/// `length` in cloud units: a length in spacings times the tree's mean spacing (measured only
/// then).
inline double resolve_length(const Length& length, const KdTree& tree) {
  return length.in_spacings() ? length.resolve(mean_spacing(tree)) : length.value;
}

/// The caller's tree, or one built into `own` over `cloud`.
inline const KdTree& tree_for(const PointCloud& cloud, const KdTree* tree, std::optional<KdTree>& own) {
  return tree != nullptr ? *tree : own.emplace(cloud.positions);
}

/// Runs `visit(i, buffer)` for every point in the tree's spatial order, in parallel, with a
/// thread-local neighbour buffer, advancing `reporter` by one a point; throws CancelledError
/// when it was cancelled.
template <typename Visit>
void for_each_point(const KdTree& tree, ProgressReporter& reporter, Visit&& visit) {
  const std::span<const std::uint32_t> order = tree.spatial_order();
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
    if (reporter.cancelled()) return;
    std::vector<Neighbor>& buffer = buffers.local();
    for (std::size_t pos = r.begin(); pos != r.end(); ++pos) visit(order[pos], buffer);
    reporter.advance(r.size());
  });
  reporter.throw_if_cancelled();
}

}  // namespace pointsurf::detail
