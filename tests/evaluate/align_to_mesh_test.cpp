// SPDX-License-Identifier: GPL-3.0-or-later
// Best-fit alignment of a scan to a mesh: a scan of a known mesh moved by a small rigid motion
// is moved back (the motion is known), far from the origin too, and then measures ~0 where it
// measured the motion before; degenerate inputs give an answer; bad parameters throw.
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/align_to_mesh.h"
#include "pointsurf/evaluate/mesh_distance.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "support/mesh_shapes.h"

namespace pointsurf {
namespace {

double rms_distance(const std::vector<Vector3d>& points, const TriangleMesh& mesh) {
  MeshDistanceParams p;
  p.sign = DistanceSign::Unsigned;
  double sum = 0.0;
  for (double d : mesh_distances(points, mesh, p).distances) sum += d * d;
  return std::sqrt(sum / static_cast<double>(points.size()));
}

// A box with unequal sides (no symmetry a small motion could slide along), its centre at `c`.
TriangleMesh box(const Vector3d& c) {
  TriangleMesh m = test::cube_mesh(1.0, Vector3d::Zero());
  for (Vector3d& v : m.vertices.positions) v = c + Vector3d(1.0 * v.x(), 0.7 * v.y(), 0.4 * v.z());
  return m;
}

TEST(AlignToMesh, MovesAScanOfTheMeshBackAndItThenMeasuresZero) {
  for (const Vector3d& c : {Vector3d(0.0, 0.0, 0.0), Vector3d(4.0e6, -2.0e6, 300.0)}) {
    const TriangleMesh mesh = box(c);
    std::vector<Vector3d> scan = sample_mesh_surface(mesh, 20000, 11);  // not the samples align_to_mesh draws
    const RigidTransform motion = RigidTransform::about(
        c, Eigen::AngleAxisd(1.5 * std::numbers::pi / 180.0, Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix(),
        Vector3d(0.02, -0.01, 0.015));
    motion.apply(std::span<Vector3d>(scan));
    const double before = rms_distance(scan, mesh);
    const RegistrationResult r = align_to_mesh(scan, mesh);
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_LT(RigidTransform::rotation_error_degrees(r.transform, motion.inverse()), 0.01);  // 0.0014: pairs across the edges
    EXPECT_LT(RigidTransform::translation_error(r.transform, motion.inverse(), c), 1e-4);
    EXPECT_GT(r.fitness, 0.99);
    r.transform.apply(std::span<Vector3d>(scan));
    const double after = rms_distance(scan, mesh);
    EXPECT_GT(before, 0.01);
    EXPECT_LT(after, 1e-4) << "before " << before;
  }
}

TEST(AlignToMesh, WorksAgainstTheVerticesOfADenseMesh) {
  const TriangleMesh mesh = [] {
    TriangleMesh m = test::grid_cube(30, 1.0);
    for (Vector3d& v : m.vertices.positions) v = Vector3d(v.x(), 0.7 * v.y(), 0.4 * v.z());
    return m;
  }();
  std::vector<Vector3d> scan = sample_mesh_surface(mesh, 20000, 11);
  const RigidTransform motion(Eigen::AngleAxisd(1.0 * std::numbers::pi / 180.0, Vector3d::UnitZ()).toRotationMatrix(), Vector3d(0.01, 0.02, 0.0));
  motion.apply(std::span<Vector3d>(scan));
  MeshAlignParams p;
  p.samples = 0;
  const RegistrationResult r = align_to_mesh(scan, mesh, p);
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_LT(RigidTransform::rotation_error_degrees(r.transform, motion.inverse()), 0.05);
  EXPECT_LT(RigidTransform::translation_error(r.transform, motion.inverse(), Vector3d::Zero()), 0.005);
}

TEST(AlignToMesh, DegenerateInputIsAnAnswerAndBadParametersThrow) {
  const TriangleMesh mesh = box(Vector3d::Zero());
  const std::vector<Vector3d> few = {Vector3d(1.0, 0.0, 0.0), Vector3d(0.0, 0.7, 0.0)};
  const RegistrationResult r = align_to_mesh(few, mesh);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.message.find("too few source points"), std::string::npos) << r.message;

  const std::vector<Vector3d> far(100, Vector3d(100.0, 0.0, 0.0));
  EXPECT_FALSE(align_to_mesh(far, mesh).converged);

  MeshAlignParams p;
  p.max_distance = Length::cloud(-1.0);
  EXPECT_THROW(align_to_mesh(few, mesh, p), UsageError);
  p.max_distance = Length::spacings(0.0);
  EXPECT_THROW(align_to_mesh(few, mesh, p), UsageError);
  p = {};
  p.max_iterations = 0;
  EXPECT_THROW(align_to_mesh(few, mesh, p), UsageError);
  EXPECT_THROW(align_to_mesh(few, TriangleMesh{}), InputError);
}

}  // namespace
}  // namespace pointsurf
