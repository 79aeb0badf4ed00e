// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/rigid_transform.h"

#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/point_cloud.h"

namespace pointsurf {
namespace {

Eigen::Matrix3d rotation(double degrees, Eigen::Vector3d axis) {
  return Eigen::AngleAxisd(degrees * M_PI / 180.0, axis.normalized()).toRotationMatrix();
}

TEST(RigidTransform, AppliesRotationThenTranslation) {
  const RigidTransform t(rotation(90, {0, 0, 1}), {1, 2, 3});
  const Eigen::Vector3d p = t.apply(Eigen::Vector3d(1, 0, 0));
  EXPECT_NEAR((p - Eigen::Vector3d(1, 3, 3)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((t.apply_normal({1, 0, 0}) - Eigen::Vector3d(0, 1, 0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(t.angle_degrees(), 90.0, 1e-12);
}

TEST(RigidTransform, InverseAndCompositionAgreeWithMatrices) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 20; ++k) {
    const RigidTransform a = RigidTransform::about({u(rng) * 5, u(rng) * 5, u(rng)}, rotation(170 * u(rng), {u(rng), u(rng), u(rng)}),
                                                   {u(rng), u(rng), u(rng)});
    const RigidTransform b(rotation(90 * u(rng), {u(rng), u(rng), 1}), {u(rng), u(rng), u(rng)});
    const Eigen::Vector3d x(u(rng), u(rng), u(rng));
    EXPECT_NEAR((a.inverse().apply(a.apply(x)) - x).norm(), 0.0, 1e-12);
    EXPECT_NEAR(((a * b).apply(x) - a.apply(b.apply(x))).norm(), 0.0, 1e-12);
    EXPECT_NEAR(((a * b).matrix() - a.matrix() * b.matrix()).cwiseAbs().maxCoeff(), 0.0, 1e-12);
    EXPECT_NEAR((a.inverse().matrix() - a.matrix().inverse()).cwiseAbs().maxCoeff(), 0.0, 1e-12);
    const RigidTransform back = RigidTransform::from_matrix(a.matrix());
    EXPECT_NEAR((back.apply(x) - a.apply(x)).norm(), 0.0, 1e-12);
  }
}

TEST(RigidTransform, KeepsSubMillimetreDigitsFarFromTheOrigin) {
  // A 30-degree turn about a point 5e6 m out: moving there and back loses nothing.
  const Eigen::Vector3d center(5.0e6, 4.0e6, 300.0);
  const RigidTransform t = RigidTransform::about(center, rotation(30, {0.2, 0.1, 1}), {0.25, -0.5, 0.125});
  const Eigen::Vector3d p = center + Eigen::Vector3d(12.345678, -3.21, 0.5);
  const Eigen::Vector3d moved = t.apply(p);
  EXPECT_NEAR((moved - center - rotation(30, {0.2, 0.1, 1}) * Eigen::Vector3d(12.345678, -3.21, 0.5) -
               Eigen::Vector3d(0.25, -0.5, 0.125)).norm(), 0.0, 1e-8);
  EXPECT_NEAR((t.inverse().apply(moved) - p).norm(), 0.0, 1e-8);
}

TEST(RigidTransform, ErrorsBetweenTransforms) {
  const RigidTransform a(rotation(10, {0, 0, 1}), {0, 0, 0});
  const RigidTransform b(rotation(12.5, {0, 0, 1}), {0, 0, 0.01});
  EXPECT_NEAR(RigidTransform::rotation_error_degrees(a, b), 2.5, 1e-9);
  EXPECT_NEAR(RigidTransform::translation_error(a, b, Eigen::Vector3d::Zero()), 0.01, 1e-12);
  EXPECT_NEAR(RigidTransform(rotation(179.9999, {1, 1, 0}), {}).angle_degrees(), 179.9999, 1e-6);
  EXPECT_NEAR(RigidTransform(rotation(1e-7, {1, 1, 0}), {}).angle_degrees(), 1e-7, 1e-12);
}

TEST(RigidTransform, MovesCloudPositionsAndNormals) {
  PointCloud c;
  c.positions = {{1, 0, 0}, {0, 1, 0}};
  c.normals = {{1, 0, 0}, {0, 0, 1}};
  RigidTransform(rotation(90, {0, 0, 1}), {0, 0, 1}).apply(c);
  EXPECT_NEAR((c.positions[0] - Eigen::Vector3d(0, 1, 1)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((c.positions[1] - Eigen::Vector3d(-1, 0, 1)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((c.normals[0] - Eigen::Vector3d(0, 1, 0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((c.normals[1] - Eigen::Vector3d(0, 0, 1)).norm(), 0.0, 1e-15);
}

TEST(RigidTransform, RefusesWhatIsNotARotation) {
  Eigen::Matrix3d mirror = Eigen::Matrix3d::Identity();
  mirror(0, 0) = -1;
  EXPECT_THROW(RigidTransform(mirror, {}), UsageError);
  EXPECT_THROW(RigidTransform(2.0 * Eigen::Matrix3d::Identity(), {}), UsageError);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(3, 0) = 1;
  EXPECT_THROW(RigidTransform::from_matrix(m), UsageError);
  m = Eigen::Matrix4d::Identity();
  m(0, 3) = std::nan("");
  EXPECT_THROW(RigidTransform::from_matrix(m), UsageError);
  // A near-rotation is projected back onto SO(3).
  Eigen::Matrix3d noisy = rotation(40, {1, 2, 3});
  noisy(0, 1) += 1e-4;
  const Eigen::Matrix3d r = RigidTransform::nearest_rotation(noisy);
  EXPECT_NEAR((r * r.transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
}

}  // namespace
}  // namespace pointsurf
