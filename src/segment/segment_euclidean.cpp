// SPDX-License-Identifier: GPL-3.0-or-later
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/segment/segment.h"
#include "segment/detail/union_find.h"

namespace pointsurf {

const FieldTable<EuclideanParams>& EuclideanParams::fields() {
  static const FieldTable<EuclideanParams> table = [] {
    using P = EuclideanParams;
    FieldTable<P> t;
    t.length("radius", &P::radius, "Cluster distance").positive().was("radius_in_spacings");
    t.integer("min_points", &P::min_points, "Fewest points of a cluster; smaller ones are unassigned").at_least(1).unit("points");
    return t;
  }();
  return table;
}

void EuclideanParams::validate() const { fields().validate(*this, "segment_euclidean"); }

SegmentResult segment_euclidean(const PointCloud& cloud, const EuclideanParams& params, const KdTree* tree) {
  constexpr std::string_view fn = "segment_euclidean";
  params.validate();
  const std::size_t n = cloud.size();
  if (n == 0) return {};
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("{}: the kd-tree holds {} points but the cloud has {}", fn, tree->size(), n));
  std::optional<KdTree> own;
  const KdTree& t = tree != nullptr ? *tree : own.emplace(cloud.positions);
  const double radius = params.radius.in_spacings() ? params.radius.resolve(mean_spacing(t)) : params.radius.value;
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
