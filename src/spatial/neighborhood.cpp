// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/spatial/neighborhood.h"

#include <cmath>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

void Neighborhood::validate(std::string_view function, int min_k) const {
  if (uses_k() && min_k > 0 && k < min_k) throw UsageError(fmt::format("{}: k must be >= {}, got {}", function, min_k, k));
  if (uses_radius() && !(radius >= 0.0 && std::isfinite(radius)))
    throw UsageError(fmt::format("{}: radius must be >= 0, got {}", function, radius));
  if (uses_radius() && radius == 0.0 && !(radius_in_spacings > 0.0 && std::isfinite(radius_in_spacings)))
    throw UsageError(fmt::format("{}: radius_in_spacings must be > 0, got {}", function, radius_in_spacings));
}

double Neighborhood::resolve_radius(const KdTree& tree) const {
  if (!uses_radius()) return 0.0;
  return radius > 0.0 ? radius : radius_in_spacings * mean_spacing(tree);
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
