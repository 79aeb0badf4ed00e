// SPDX-License-Identifier: GPL-3.0-or-later
#include <optional>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/segment/segment.h"
#include "segment/detail/union_find.h"

namespace pointsurf {

const FieldTable<SurfaceTypeParams>& SurfaceTypeParams::fields() {
  static const FieldTable<SurfaceTypeParams> table = [] {
    using P = SurfaceTypeParams;
    FieldTable<P> t;
    t.integer("k", &P::k, "Neighbours per point (the graph's edges)").at_least(2).unit("points");
    t.integer("min_points", &P::min_points, "Fewest points of a region; smaller ones are unassigned").at_least(1).unit("points");
    return t;
  }();
  return table;
}

void SurfaceTypeParams::validate() const {
  if (k < 2) throw UsageError(fmt::format("segment_surface_types: k must be >= 2, got {}", k));
  fields().validate(*this, "segment_surface_types");
}

SegmentResult segment_surface_types(const PointCloud& cloud, const SurfaceTypeParams& params, const KdTree* tree) {
  constexpr std::string_view fn = "segment_surface_types";
  params.validate();
  const std::size_t n = cloud.size();
  if (n == 0) return {};
  const ScalarField* types = cloud.fields.find("surface_type");
  if (types == nullptr) throw UsageError(fmt::format("{}: the cloud has no \"surface_type\" field (run the curvature stage first)", fn));
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("{}: the kd-tree holds {} points but the cloud has {}", fn, tree->size(), n));
  std::optional<KdTree> own;
  const KdTree& t = tree != nullptr ? *tree : own.emplace(cloud.positions);
  const NeighborLists graph = t.knn_all({}, std::size_t(params.k) + 1);
  const std::vector<double>& type = types->values;
  detail::UnionFind sets(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    if (type[i] == 0.0) continue;
    for (const Neighbor& nb : graph[i])
      if (type[nb.index] == type[i]) sets.unite(i, nb.index);
  }
  std::vector<std::int64_t> groups(n);
  for (std::uint32_t i = 0; i < n; ++i) groups[i] = type[i] == 0.0 ? -1 : std::int64_t(sets.find(i));
  return number_segments(cloud.positions, groups, params.min_points);
}

}  // namespace pointsurf
