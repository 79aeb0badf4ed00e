// SPDX-License-Identifier: GPL-3.0-or-later
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/segment/segment.h"
#include "segment/detail/union_find.h"

namespace pointsurf {

void EuclideanParams::validate() const {
  constexpr std::string_view fn = "segment_euclidean";
  if (!std::isfinite(radius) || radius < 0.0) throw UsageError(fmt::format("{}: radius must be >= 0 (cloud units), got {}", fn, radius));
  if (radius == 0.0 && !(std::isfinite(radius_in_spacings) && radius_in_spacings > 0.0))
    throw UsageError(fmt::format("{}: radius_in_spacings must be > 0, got {}", fn, radius_in_spacings));
}

SegmentResult segment_euclidean(const PointCloud& cloud, const EuclideanParams& params, const KdTree* tree) {
  constexpr std::string_view fn = "segment_euclidean";
  params.validate();
  const std::size_t n = cloud.size();
  if (n == 0) return {};
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("{}: the kd-tree holds {} points but the cloud has {}", fn, tree->size(), n));
  std::optional<KdTree> own;
  const KdTree& t = tree != nullptr ? *tree : own.emplace(cloud.positions);
  const double radius = params.radius > 0.0 ? params.radius : params.radius_in_spacings * mean_spacing(t);
  detail::UnionFind sets(n);
  if (radius > 0.0) {
    const NeighborLists graph = t.radius_all({}, radius);
    for (std::uint32_t i = 0; i < n; ++i)
      for (const Neighbor& nb : graph[i]) sets.unite(i, nb.index);
  } else {
    // Every point at one place: one cluster.
    for (std::uint32_t i = 1; i < n; ++i) sets.unite(0, i);
  }
  std::vector<std::int64_t> groups(n);
  for (std::uint32_t i = 0; i < n; ++i) groups[i] = sets.find(i);
  return number_segments(cloud.positions, groups, params.min_points);
}

}  // namespace pointsurf
