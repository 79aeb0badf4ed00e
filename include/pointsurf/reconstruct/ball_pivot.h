// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Ball pivoting surface reconstruction (Bernardini, Mittleman, Rushmeier, Silva, Taubin:
// "The Ball-Pivoting Algorithm for Surface Reconstruction", IEEE TVCG 5(4), 1999).
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/reconstruct/fill_holes.h"
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
  // A triangle is accepted only when its normal is within this angle of each of its vertex
  // normals, degrees (default 100). 90 is the paper's rule (same side); a little more keeps the
  // thin triangles that straddle a 90-degree edge, whose normal is almost that of one face.
  double max_normal_angle_deg = 100.0;
  // ... and within this angle of the mean of its vertex normals, degrees (default 65). Triangles
  // across a 90-degree edge are within 63.4; a triangle joining two parallel sheets edge-on,
  // whose vertex normals agree with each other but not with it, is near 90.
  double max_mean_normal_angle_deg = 65.0;
  // Final pass: holes up to this perimeter (local spacings) are closed by fill_holes() (where
  // the ball could not rest on a hole's corners, typically at a sharp edge); 0: off.
  double max_hole_perimeter_in_spacings = HoleFillParams{}.max_perimeter_in_spacings;
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<BallPivotParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

/// Interpolating mesh through the points of `cloud` by rolling balls of the given radii over
/// it: a triangle is created wherever a ball touches three points and holds no other point.
/// Follows Bernardini et al. 1999: seed triangle search, pivoting of the front edges, join
/// and glue, then a new pass re-pivoting the boundary edges with each larger radius (only where
/// the larger ball rests empty on the edge's triangle), then the small-hole pass above.
/// Besides the normal angles, a triangle never joins two vertices with normals more than 120
/// degrees apart (opposite sides of a thin plate), nor two vertices of parallel sheets: normals
/// within 30 degrees but the chord between them off their common tangent plane by more than 20
/// degrees and more than one mean spacing. Points of such another sheet neither stop the ball
/// nor are hit by it, so each of two sheets closer than the ball's diameter is still meshed.
///
/// `cloud` needs oriented normals (N×3, one per point): they choose the side the ball sits on
/// and the triangles' orientation (counter-clockwise seen from the side the normals point to).
/// The result's mesh has the cloud's points as vertices (with normals, colours and fields), so
/// vertex i is point i; duplicate points are left unused.
/// `tree`: a KdTree over cloud.positions to reuse (one is built when null).
/// `progress`: fraction done in [0, 1]; returning false throws CancelledError.
///
/// Throws UsageError for fewer than 3 points, missing normals, or a radius (or
/// radius-in-spacings) that is not > 0 and finite, or a normal angle outside (0, 180].
/// Throws ComputeError when all points coincide. Collinear input gives an empty mesh.
/// Time about O(N · k) for k points within 2r. The front is sequential; the neighbour lists of
/// the first (smallest) radius are computed beforehand in parallel with oneTBB (when it is at
/// most 3 mean spacings), about 4 bytes per neighbour within 3 radii.
/// Thread-safe: reads its inputs only.
ReconstructionResult reconstruct_ball_pivoting(const PointCloud& cloud, const BallPivotParams& params = {},
                                               const KdTree* tree = nullptr,
                                               const ProgressCallback& progress = {});

}  // namespace pointsurf
