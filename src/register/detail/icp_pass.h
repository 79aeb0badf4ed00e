// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// One correspondence pass of ICP and the two closed-form / linearised updates, in a frame
// centred on the target's centroid.
//
// The source is copied once, in Morton order, relative to that centre: every pass then reads it
// linearly, its nearest-neighbour queries stay in cache, and the sums that make up the normal
// equations are of coordinates of the object's own size, so a scan 1e6 m from the origin loses
// no digits. Sums are taken per fixed block of points and the blocks added in order, so the
// answer does not depend on how the threads were scheduled.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/register/icp.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::detail {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// What one pass gathers, over one block or the whole source.
struct IcpSums {
  std::size_t near = 0;        // pairs within the max distance (fitness)
  double near_squared = 0.0;   // their squared distances
  std::size_t used = 0;        // pairs that also passed the normal check (the ones solved for)
  double used_squared = 0.0;
  Eigen::Vector3d sum_p = Eigen::Vector3d::Zero();   // point-to-point: sums of source and target
  Eigen::Vector3d sum_q = Eigen::Vector3d::Zero();   // points and of their outer products p q^T
  Eigen::Matrix3d sum_pq = Eigen::Matrix3d::Zero();
  Matrix6d ata = Matrix6d::Zero();                   // point-to-plane: normal equations
  Vector6d atb = Vector6d::Zero();

  void add(const IcpSums& o);
};

/// What a pass accumulates beyond the counts.
enum class IcpSystem : std::uint8_t { None, PointToPoint, PointToPlane };

/// The source and target as one ICP run reads them.
class IcpFrame {
public:
  /// `name` prefixes error messages. Throws UsageError when the tree does not match the target,
  /// InputError for a non-finite source point. Keeps source normals when `with_normals`.
  IcpFrame(const char* name, const PointCloud& source, const PointCloud& target, const KdTree& target_tree, bool with_normals);

  const Eigen::Vector3d& center() const noexcept { return center_; }
  /// RMS distance of the target's points from the centre (1 when they coincide): the length
  /// that makes the rotation and translation unknowns of the point-to-plane system comparable.
  double scale() const noexcept { return scale_; }
  std::size_t source_size() const noexcept { return source_.size(); }

  /// Pairs every source point x (local) moved to R x + t with its nearest target point within
  /// `max_distance`; with `cos_max_normal` > -1, pairs whose normals (the source's turned by R)
  /// have a smaller cosine are not used. Parallel, deterministic.
  IcpSums pass(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation, double max_distance, double cos_max_normal,
               IcpSystem system);

private:
  const PointCloud& target_;
  const KdTree& tree_;
  Eigen::Vector3d center_ = Eigen::Vector3d::Zero();
  double scale_ = 1.0;
  std::vector<Eigen::Vector3d> source_;    // relative to center_, Morton order
  std::vector<Eigen::Vector3d> normals_;   // same order, empty unless asked for
  std::vector<IcpSums> blocks_;
};

/// The rigid update (R, t) minimising the point-to-point distances of the pairs (Kabsch, by SVD
/// of the cross-covariance).
void solve_point_to_point(const IcpSums& sums, Eigen::Matrix3d& rotation, Eigen::Vector3d& translation);
/// The rigid update minimising the linearised point-to-plane distances. Directions the pairs do
/// not constrain (a plane's in-plane slide) are left unchanged instead of guessed.
void solve_point_to_plane(const IcpSums& sums, double scale, Eigen::Matrix3d& rotation, Eigen::Vector3d& translation);

}  // namespace pointsurf::detail
