// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The neighbourhood a per-point stage looks at (kind, k, radius): one type for normals,
// curvature and every later per-point stage, with its one check and its one query.
#include <cstddef>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/length.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

enum class NeighborhoodKind { Knn, Radius, Hybrid };
/// "knn", "radius", "hybrid".
const EnumNames<NeighborhoodKind>& neighborhood_kind_names();

struct Neighborhood {
  NeighborhoodKind kind = NeighborhoodKind::Knn;
  int k = 30;                       // neighbours (Knn; Hybrid: at most k within the radius)
  Length radius = Length::spacings(3.0);  // (Radius, Hybrid) in cloud units or mean spacings, > 0

  bool uses_k() const noexcept { return kind != NeighborhoodKind::Radius; }
  bool uses_radius() const noexcept { return kind != NeighborhoodKind::Knn; }
  /// Throws UsageError "FUNCTION: k must be >= MIN_K, got ..." (when k is used; skipped for
  /// min_k <= 0, where the caller checks k itself), or for a radius that is not > 0 and finite
  /// (when the radius is used).
  void validate(std::string_view function, int min_k) const;
  /// The search radius in cloud units (a radius in spacings times the tree's mean spacing); 0
  /// for Knn.
  double resolve_radius(const KdTree& tree) const;
  /// The neighbours of `p` into `out` (nearest first) with `k_used` and `radius_used`.
  void query(const KdTree& tree, const Eigen::Vector3d& p, std::size_t k_used, double radius_used, std::vector<Neighbor>& out) const;
};

}  // namespace pointsurf
