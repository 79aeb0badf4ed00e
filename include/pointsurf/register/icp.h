// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Iterative closest point, point-to-point (Besl and McKay 1992; closed form by SVD) and
// point-to-plane (Chen and Medioni 1992; linearised least squares), with the target's kd-tree.
// Pairs are rejected by distance and, the paper's improvement, by the angle between the two
// normals, which keeps ICP from locking onto the wrong side of thin parts and onto crossings:
// when the nearest target point faces the other way, the nearest one among the 32 nearest within
// the max distance that faces the same way is paired instead (none: the source point is left
// out). The normals must be oriented consistently (outward, or towards the scanner).
//
// Each iteration pairs every source point with the target in parallel (oneTBB, source points in
// Morton order) and sums the normal equations per fixed block of points, the blocks added in
// order: the answer is the same on any number of threads.
#include <cstddef>
#include <cstdint>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/register/result.h"

namespace pointsurf {

class KdTree;

enum class IcpMetric : std::uint8_t { PointToPoint = 0, PointToPlane = 1 };
/// "point", "plane".
const EnumNames<IcpMetric>& icp_metric_names();
/// "point", "plane" (icp_metric_names()).
const char* icp_metric_name(IcpMetric metric) noexcept;

struct IcpParams {
  IcpMetric metric = IcpMetric::PointToPlane;
  Length max_distance = Length::spacings(3.0);  // pairs farther apart are rejected, cloud
                                       // units or the source's mean spacings, > 0
  double max_normal_deg = 45.0;        // pairs whose normals differ more are rejected, degrees;
                                       // 180 disables the check (plain ICP)
  std::size_t max_iterations = 50;     // iterations at most, in [1, 100000]
  double relative_fitness = 1e-6;      // converged when the number of pairs used and their RMSE
  double relative_rmse = 1e-6;         // change by less than these relative amounts between two
                                       // iterations, when an update moves the points by less
                                       // than 0.001 x the max distance (RMS), or when ICP comes
                                       // back to where it was two updates before (a 2-cycle)
  /// Key, unit, range and doc of each field (core/fields.h): icp, icp_distance, max_normal_deg,
  /// iterations (the keys of the register stages).
  static const FieldTable<IcpParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// Refines `initial` (mapping source onto target) by ICP. Point-to-plane needs the target's
/// normals; the normal-angle rejection needs both clouds' normals (UsageError when missing and
/// the check is on). `target_tree` is built over the target's positions. Works in a frame centred
/// on the target's centroid. Every loop is bounded; a run that does not converge (iteration cap,
/// fewer than 3 (point) or 6 (plane) pairs left) returns with converged = false and the reason in
/// `message`. The result's fitness and inlier RMSE are evaluate_registration's at the final
/// transform and the max distance used; `correspondences` counts the pairs that passed the normal
/// check. Thread-safe; parallel inside.
RegistrationResult icp(const PointCloud& source, const PointCloud& target, const KdTree& target_tree, const RigidTransform& initial,
                       const IcpParams& params, const ProgressCallback& progress = {});

/// Fitness and inlier RMSE of `transform` (source onto target) at `max_distance` (> 0, else
/// UsageError): the scores every step reports, evaluated the same way everywhere. Normals are not
/// looked at; correspondences = the source points within the distance, iterations 0, converged
/// true. Parallel; thread-safe.
RegistrationResult evaluate_registration(const PointCloud& source, const PointCloud& target, const KdTree& target_tree,
                                         const RigidTransform& transform, double max_distance);

}  // namespace pointsurf
