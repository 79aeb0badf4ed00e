// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Checks and defaults shared by the cleaning functions.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string_view>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
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

/// Throws UsageError unless `value` is finite and >= 0 (`positive`: > 0).
inline void check_length(std::string_view function, std::string_view name, double value, bool positive) {
  if (!std::isfinite(value) || value < 0.0 || (positive && value == 0.0))
    throw UsageError(fmt::format("{}: {} must be {} (cloud units), got {}", function, name, positive ? "> 0" : ">= 0", value));
}

/// Throws UsageError unless `value` is finite and > 0.
inline void check_positive(std::string_view function, std::string_view name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) throw UsageError(fmt::format("{}: {} must be > 0, got {}", function, name, value));
}

/// `length` when > 0, else `in_spacings` times the tree's mean spacing.
inline double resolve_length(double length, double in_spacings, const KdTree& tree) {
  return length > 0.0 ? length : in_spacings * mean_spacing(tree);
}

/// The caller's tree, or one built into `own` over `cloud`.
inline const KdTree& tree_for(const PointCloud& cloud, const KdTree* tree, std::optional<KdTree>& own) {
  return tree != nullptr ? *tree : own.emplace(cloud.positions);
}

}  // namespace pointsurf::detail
