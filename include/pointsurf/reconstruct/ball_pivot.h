// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Ball pivoting surface reconstruction (Bernardini, Mittleman, Rushmeier, Silva, Taubin:
// "The Ball-Pivoting Algorithm for Surface Reconstruction", IEEE TVCG 5(4), 1999).
#include <vector>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/reconstruct/reconstruction.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

struct BallPivotParams {
  // Ball radii, cloud units, used in increasing order (sorted and deduplicated). Each must be
  // > 0. Empty (default): radii_in_spacings × the cloud's mean spacing.
  std::vector<double> radii;
  // Used when `radii` is empty: multiples of the mean spacing. Default {1.5, 3, 6}: the
  // smallest ball closes well-sampled areas, the larger ones fill holes left by sparser areas.
  std::vector<double> radii_in_spacings = {1.5, 3.0, 6.0};
  // A triangle is accepted only when its normal and each of its vertex normals are within this
  // angle, degrees (default 90: they point to the same side). Smaller rejects more triangles
  // across thin sheets and sharp folds.
  double max_normal_angle_deg = 90.0;
};

/// Interpolating mesh through the points of `cloud` by rolling balls of the given radii over
/// it: a triangle is created wherever a ball touches three points and holds no other point.
/// Follows Bernardini et al. 1999: seed triangle search, pivoting of the front edges, join
/// and glue, then a new pass re-pivoting the boundary edges with each larger radius.
///
/// `cloud` needs oriented normals (N×3, one per point): they choose the side the ball sits on
/// and the triangles' orientation (counter-clockwise seen from the side the normals point to).
/// The result's mesh has the cloud's points as vertices (with normals, colours and fields), so
/// vertex i is point i; duplicate points are left unused.
/// `tree`: a KdTree over cloud.positions to reuse (one is built when null).
/// `progress`: fraction done in [0, 1]; returning false throws CancelledError.
///
/// Throws UsageError for fewer than 3 points, missing normals, or a radius (or
/// radius-in-spacings) that is not > 0 and finite, or a max_normal_angle_deg outside (0, 180].
/// Throws ComputeError when all points coincide. Collinear input gives an empty mesh.
/// Time about O(N · k) for k points within 2r; serial (the front is sequential).
/// Thread-safe: reads its inputs only.
ReconstructionResult reconstruct_ball_pivoting(const PointCloud& cloud, const BallPivotParams& params = {},
                                               const KdTree* tree = nullptr,
                                               const ProgressCallback& progress = {});

}  // namespace pointsurf
