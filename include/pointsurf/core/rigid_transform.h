// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A rigid motion x -> R x + t: what registration estimates and the `transform` stage applies.
//
// Georeferenced clouds sit 1e6..1e7 m from the origin. Estimating R and t there directly loses
// digits (a covariance of raw coordinates cancels catastrophically), so estimators work in a
// frame centred on a local origin c and describe their answer with `about(c, R, t_local)`:
// x -> R (x - c) + c + t_local. The stored (R, t) is the same motion in world coordinates;
// `apply` evaluates it as R (x - c) + (c + t_local) when built that way, so a point at 1e6 m
// moved by a small motion keeps its sub-millimetre digits.
#include <span>
#include <string>

#include <Eigen/Core>

namespace pointsurf {

struct PointCloud;

class RigidTransform {
 public:
  RigidTransform() = default;  // identity
  /// x -> R x + t. Throws UsageError when R is not a rotation (orthonormal within 1e-6,
  /// determinant +1).
  RigidTransform(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation);
  /// x -> R (x - center) + center + local_translation: the motion an estimator finds in a frame
  /// centred on `center`. Kept in that form so that applying it loses nothing far from the origin.
  static RigidTransform about(const Eigen::Vector3d& center, const Eigen::Matrix3d& rotation,
                              const Eigen::Vector3d& local_translation);
  /// From a 4x4 matrix [R t; 0 0 0 1]; throws UsageError naming what is wrong.
  static RigidTransform from_matrix(const Eigen::Matrix4d& m);
  /// Projects a near-rotation (accumulated round-off, a least-squares estimate) onto SO(3) by SVD.
  static Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& m);

  const Eigen::Matrix3d& rotation() const noexcept { return rotation_; }
  /// World translation t of x -> R x + t.
  Eigen::Vector3d translation() const;
  Eigen::Matrix4d matrix() const;

  Eigen::Vector3d apply(const Eigen::Vector3d& p) const noexcept { return rotation_ * (p - center_) + offset_; }
  Eigen::Vector3d apply_normal(const Eigen::Vector3d& n) const noexcept { return rotation_ * n; }
  /// Moves positions and normals in place (parallel).
  void apply(PointCloud& cloud) const;
  void apply(std::span<Eigen::Vector3d> points) const;

  RigidTransform inverse() const;
  /// (a * b)(x) = a(b(x)): b first.
  friend RigidTransform operator*(const RigidTransform& a, const RigidTransform& b);

  /// Rotation angle in degrees, in [0, 180].
  double angle_degrees() const;
  /// Angle (degrees) of the relative rotation between two transforms: the rotation error of an
  /// estimate against the truth.
  static double rotation_error_degrees(const RigidTransform& a, const RigidTransform& b);
  /// Distance between where the two transforms send `at` (cloud units): the translation error
  /// measured at a point of interest (the cloud's centroid), independent of the world origin.
  static double translation_error(const RigidTransform& a, const RigidTransform& b, const Eigen::Vector3d& at);

  /// One line for logs and reports: angle, axis and translation.
  std::string describe() const;

 private:
  // x -> R (x - center_) + offset_, with offset_ = center_ + local translation.
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();
};

}  // namespace pointsurf
