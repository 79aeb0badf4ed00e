// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The neighbourhood a per-point stage looks at (kind, k, radius): one type for normals,
// curvature and every later per-point stage, with its one check and its one query.
#include <cstddef>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

enum class NeighborhoodKind { Knn, Radius, Hybrid };

struct Neighborhood {
  NeighborhoodKind kind = NeighborhoodKind::Knn;
  int k = 30;                       // neighbours (Knn; Hybrid: at most k within the radius)
  double radius = 0.0;              // cloud units (Radius, Hybrid); 0: radius_in_spacings x mean spacing
  double radius_in_spacings = 3.0;  // used when radius == 0

  bool uses_k() const noexcept { return kind != NeighborhoodKind::Radius; }
  bool uses_radius() const noexcept { return kind != NeighborhoodKind::Knn; }
  /// Throws UsageError "FUNCTION: k must be >= MIN_K, got ..." (when k is used; skipped for
  /// min_k <= 0, where the caller checks k itself), or for a negative or non-finite radius or
  /// radius_in_spacings <= 0 (when the radius is used).
  void validate(std::string_view function, int min_k) const;
  /// The search radius in cloud units: `radius`, or radius_in_spacings x the tree's mean
  /// spacing; 0 for Knn.
  double resolve_radius(const KdTree& tree) const;
  /// The neighbours of `p` into `out` (nearest first) with `k_used` and `radius_used`.
  void query(const KdTree& tree, const Eigen::Vector3d& p, std::size_t k_used, double radius_used, std::vector<Neighbor>& out) const;
};

}  // namespace pointsurf
