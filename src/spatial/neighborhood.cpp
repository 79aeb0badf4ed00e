// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/spatial/neighborhood.h"

#include <cmath>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

const EnumNames<NeighborhoodKind>& neighborhood_kind_names() {
  static const EnumNames<NeighborhoodKind> names{{{NeighborhoodKind::Knn, "knn"}, {NeighborhoodKind::Radius, "radius"}, {NeighborhoodKind::Hybrid, "hybrid"}}};
  return names;
}

void Neighborhood::validate(std::string_view function, int min_k) const {
  if (uses_k() && min_k > 0 && k < min_k) throw UsageError(fmt::format("{}: k must be >= {}, got {}", function, min_k, k));
  if (uses_radius() && !(radius.value > 0.0 && std::isfinite(radius.value)))
    throw UsageError(fmt::format("{}: radius must be > 0, got {}", function, radius.text()));
}

double Neighborhood::resolve_radius(const KdTree& tree) const {
  if (!uses_radius()) return 0.0;
  return radius.in_spacings() ? radius.value * mean_spacing(tree) : radius.value;
}

void Neighborhood::query(const KdTree& tree, const Eigen::Vector3d& p, std::size_t k_used, double radius_used,
                         std::vector<Neighbor>& out) const {
  switch (kind) {
    case NeighborhoodKind::Knn: tree.knn(p, k_used, out); break;
    case NeighborhoodKind::Radius: tree.radius(p, radius_used, out); break;
    case NeighborhoodKind::Hybrid: tree.hybrid(p, k_used, radius_used, out); break;
  }
}

}  // namespace pointsurf
