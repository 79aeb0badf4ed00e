// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Pose graph: the absolute poses of n scans from relative transforms measured between pairs of
// them (registration of every overlapping pair), by least squares on the poses. Each edge says
// "scan i maps onto scan j by T_ij", weighted by an information matrix built from the point
// pairs behind it, so that its cost is the sum of squared displacements of those points: an
// edge over many well-spread pairs pulls hard, one over a thin strip of overlap pulls only in
// the directions it constrains. Gauss-Newton on small motions of the poses (rotation vector and
// translation), the first scan fixed; the graph formulation of Lu and Milios (1997) with
// Open3D's information from point pairs (Choi, Zhou, Koltun 2015), without its line process:
// uncertain edges (loop closures) whose residual stays large are dropped and the graph solved
// again, at most once per such edge.
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/results.h"
#include "pointsurf/core/rigid_transform.h"

namespace pointsurf {

class KdTree;

using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct PoseGraphEdge {
  std::size_t source = 0;            // scan index i
  std::size_t target = 0;            // scan index j (!= i)
  RigidTransform transform;          // T_ij: maps scan i's points onto scan j (in scan j's frame)
  Matrix6d information = Matrix6d::Identity();  // weight of the residual (rotation vector,
                                     // translation) of T_ij in the graph's centred frame (see
                                     // PoseGraphParams::center); information_from_pairs gives
                                     // the sum over point pairs; its translation block's trace / 3
                                     // is taken as the number of pairs
  bool uncertain = false;            // a loop closure that may be wrong: dropped when its
                                     // residual exceeds prune_distance after a solve
};

struct PoseGraphParams {
  std::size_t fixed = 0;              // the scan whose pose is kept (usually the first)
  std::size_t max_iterations = 50;    // Gauss-Newton iterations at most, per solve
  double tolerance = 1e-10;           // converged when an iteration lowers the cost by less
                                      // than this share of it
  double prune_distance = 0.0;        // an uncertain edge whose RMS point displacement after
                                      // the solve exceeds this is dropped, cloud units; 0 keeps all
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // origin of the frame the residuals and
                                      // information are expressed in (a point near the scans,
                                      // so 1e6 m coordinates lose nothing)
  /// Key, unit, range and doc of each field (core/fields.h); no stage offers them.
  static const FieldTable<PoseGraphParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

struct PoseGraphResult {
  std::vector<RigidTransform> poses;  // pose i maps scan i into the fixed scan's frame
  double initial_cost = 0.0;          // sum over edges of r^T Lambda r before, squared cloud units
  double cost = 0.0;                  // after (smaller is better)
  std::size_t iterations = 0;         // Gauss-Newton iterations over all solves
  bool converged = false;             // the last solve met `tolerance` within max_iterations
  std::vector<std::size_t> pruned;    // indices of the edges dropped (uncertain, residual too large)
  std::vector<double> edge_rms;       // per edge: RMS displacement of its points under the final
                                      // poses, cloud units (smaller is better)

  /// The reported members (core/results.h): the cost before and after, the iterations.
  static const ResultTable<PoseGraphResult>& results();
};

/// Optimises the poses of `initial_poses.size()` scans so that every edge's relative transform
/// agrees with them in the least-squares sense of its information. Every scan must be
/// connected to the fixed one through edges (UsageError naming the first that is not), as must
/// stay true after pruning (an uncertain edge whose removal would disconnect the graph is
/// kept). Bounded: at most max_iterations per solve and one solve per pruned edge plus one.
/// Thread-safe (pure function).
PoseGraphResult optimize_pose_graph(const std::vector<RigidTransform>& initial_poses, const std::vector<PoseGraphEdge>& edges,
                                    const PoseGraphParams& params = {});

/// The information of a registration from its point pairs: sum over the pairs (source point
/// moved by `transform`, its nearest target point within `max_distance`) of J^T J, with
/// J = [-[q]x  I] at the moved point q - center: the quadratic form that gives the summed
/// squared displacement of those points under a small motion (rotation vector, translation)
/// about `center`. `target_tree` is built over `target.positions`. Parallel; thread-safe.
Matrix6d information_from_pairs(const PointCloud& source, const KdTree& target_tree, const RigidTransform& transform,
                                double max_distance, const Eigen::Vector3d& center);

}  // namespace pointsurf
