// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/rigid_transform.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/point_cloud.h"

namespace pointsurf {
namespace {

constexpr double kRadToDeg = 57.295779513082320876798;

double rotation_angle(const Eigen::Matrix3d& r) {
  // The trace formula loses precision near 0 and 180 degrees; atan2 of the skew part and the
  // trace keeps it everywhere.
  const double s = 0.5 * Eigen::Vector3d(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1)).norm();
  const double c = 0.5 * (r.trace() - 1.0);
  return std::atan2(s, c) * kRadToDeg;
}

}  // namespace

RigidTransform::RigidTransform(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation)
    : rotation_(rotation), offset_(translation) {
  if (!rotation.allFinite() || !translation.allFinite()) throw UsageError("transform: the matrix has a non-finite entry");
  const double err = (rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > 1e-6 || rotation.determinant() < 0.0)
    throw UsageError(fmt::format("transform: the 3x3 block is not a rotation (orthonormality error {:.3g}, determinant {:.6g})", err,
                                 rotation.determinant()));
}

RigidTransform RigidTransform::about(const Eigen::Vector3d& center, const Eigen::Matrix3d& rotation,
                                     const Eigen::Vector3d& local_translation) {
  RigidTransform t(rotation, Eigen::Vector3d::Zero());
  if (!center.allFinite() || !local_translation.allFinite()) throw UsageError("transform: non-finite centre or translation");
  t.center_ = center;
  t.offset_ = center + local_translation;
  return t;
}

RigidTransform RigidTransform::from_matrix(const Eigen::Matrix4d& m) {
  if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0)
    throw UsageError("transform: the last row of the 4x4 matrix must be 0 0 0 1");
  return RigidTransform(m.topLeftCorner<3, 3>(), m.topRightCorner<3, 1>());
}

Eigen::Matrix3d RigidTransform::nearest_rotation(const Eigen::Matrix3d& m) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

Eigen::Vector3d RigidTransform::translation() const { return offset_ - rotation_ * center_; }

Eigen::Matrix4d RigidTransform::matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = rotation_;
  m.topRightCorner<3, 1>() = translation();
  return m;
}

void RigidTransform::apply(std::span<Eigen::Vector3d> points) const {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) points[i] = apply(points[i]);
  });
}

void RigidTransform::apply(PointCloud& cloud) const {
  apply(std::span<Eigen::Vector3d>(cloud.positions));
  for (Eigen::Vector3d& n : cloud.normals) n = rotation_ * n;
}

RigidTransform RigidTransform::inverse() const {
  // y = R (x - c) + o  <=>  x = R^T (y - o) + c.
  RigidTransform t;
  t.rotation_ = rotation_.transpose();
  t.center_ = offset_;
  t.offset_ = center_;
  return t;
}

RigidTransform operator*(const RigidTransform& a, const RigidTransform& b) {
  // a(b(x)) = Ra (Rb (x - cb) + ob - ca) + oa: keep b's centre.
  RigidTransform t;
  t.rotation_ = RigidTransform::nearest_rotation(a.rotation_ * b.rotation_);
  t.center_ = b.center_;
  t.offset_ = a.rotation_ * (b.offset_ - a.center_) + a.offset_;
  return t;
}

double RigidTransform::angle_degrees() const { return rotation_angle(rotation_); }

double RigidTransform::rotation_error_degrees(const RigidTransform& a, const RigidTransform& b) {
  return rotation_angle(a.rotation_.transpose() * b.rotation_);
}

double RigidTransform::translation_error(const RigidTransform& a, const RigidTransform& b, const Eigen::Vector3d& at) {
  return (a.apply(at) - b.apply(at)).norm();
}

std::string RigidTransform::describe() const {
  const Eigen::AngleAxisd aa(rotation_);
  const Eigen::Vector3d t = translation();
  return fmt::format("rotation {:.4g} degrees about ({:.4f}, {:.4f}, {:.4f}), translation ({:.6g}, {:.6g}, {:.6g})", angle_degrees(),
                     aa.axis().x(), aa.axis().y(), aa.axis().z(), t.x(), t.y(), t.z());
}

}  // namespace pointsurf
