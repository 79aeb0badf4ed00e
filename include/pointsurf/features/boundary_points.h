// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Boundary points of a sampled surface by the angular-gap test: a point on the rim of an open
// surface (the border of a terrain tile, the edge of a window in a facade) has all its
// neighbours on one side, so seen from it in its tangent plane they leave a wide empty sector.
// Used by the reconstruct stage to tell border loops from holes; segmentation reuses it.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/results.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

struct BoundaryParams {
  int k = 30;                  // neighbours per point, >= 4 (with 16, random samples leave gaps
                               // over 90 degrees around 21 % of interior points; with 30, 0.5 %)
  double min_gap_deg = 90.0;   // a point is on the boundary when the largest angle between
                               // consecutive neighbours around it, in its tangent plane, exceeds
                               // this (PCL's BoundaryEstimation default, pi / 2), in (0, 360)
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<BoundaryParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

struct BoundaryResult {
  std::vector<std::uint8_t> boundary;  // per point: 1 on the boundary
  std::vector<double> gap_deg;         // per point: the largest angular gap, degrees (360: no
                                       // usable neighbour)
  std::size_t count = 0;               // boundary points

  /// The reported members (core/results.h).
  static const ResultTable<BoundaryResult>& results();
};

/// The angular-gap test per point (in parallel, oneTBB, in the tree's spatial order): the `k`
/// nearest neighbours (exact copies of the point skipped) are projected onto the point's tangent
/// plane, the plane normal to its normal (the cloud's when it has non-zero normals, else the PCA
/// normal of the neighbourhood), and sorted by angle; the largest gap between consecutive ones,
/// the wrap-around included, is compared with `min_gap_deg`. Interior points of a uniformly
/// sampled surface have gaps near 360 / k (random samples about 2.5x that); rim points 180 and
/// more; corners of a rim 270.
/// Reuses `tree` if given (over cloud.positions). Throws UsageError for a parameter out of range.
/// Deterministic; thread-safe (reads `cloud` only).
BoundaryResult detect_boundary_points(const PointCloud& cloud, const BoundaryParams& params = {}, const KdTree* tree = nullptr);

}  // namespace pointsurf
