// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/reconstruct/fill_holes.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "support/mesh_shapes.h"

namespace pointsurf {
namespace {

// Removes the triangles with a vertex within `radius` of `at`: one hole of about that size.
TriangleMesh cut(TriangleMesh mesh, const Vector3d& at, double radius) {
  std::vector<Triangle> kept;
  for (const Triangle& t : mesh.triangles) {
    bool near = false;
    for (int c = 0; c < 3; ++c) near = near || (mesh.vertices.positions[std::size_t(t[c])] - at).norm() < radius;
    if (!near) kept.push_back(t);
  }
  mesh.triangles = std::move(kept);
  return mesh;
}

double mean_edge(const TriangleMesh& mesh) {
  double sum = 0.0;
  for (const Triangle& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) sum += (mesh.vertices.positions[std::size_t(t[c])] - mesh.vertices.positions[std::size_t(t[(c + 1) % 3])]).norm();
  return sum / double(3 * mesh.triangles.size());
}

// An n x n grid in the plane z = 0, normals +z.
TriangleMesh grid(int n) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.positions.emplace_back(i, j, 0.0);
  const auto id = [n](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.triangles.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      m.triangles.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  return m;
}

TEST(FillHoles, ClosesASmallHoleOnASphereWithTrianglesOnTheSurface) {
  const TriangleMesh whole = test::icosphere_mesh(4, 1.0);  // 5120 faces, edge ~0.06
  TriangleMesh holed = cut(whole, Vector3d(0, 0, 1), 0.15);
  const MeshTopology before = analyze_topology(holed);
  ASSERT_EQ(before.boundary_loops.size(), 1u);
  const double perimeter_in_edges = before.boundary_loops.front().length / mean_edge(holed);
  ASSERT_LT(perimeter_in_edges, 20.0);
  const std::size_t faces_before = holed.triangles.size();
  const HoleFillStats s = fill_holes(holed);
  EXPECT_EQ(s.holes_before, 1u);
  EXPECT_EQ(s.holes_filled, 1u);
  EXPECT_EQ(s.holes_after, 0u);
  EXPECT_EQ(holed.triangles.size(), faces_before + s.triangles_added - s.triangles_removed);
  const MeshTopology after = analyze_topology(holed);
  EXPECT_TRUE(after.watertight());
  EXPECT_EQ(after.genus(), 0);
  // The new triangles face outward, like the sphere's.
  for (std::size_t t = faces_before; t < holed.triangles.size(); ++t) {
    const Triangle& tri = holed.triangles[t];
    const Vector3d& a = holed.vertices.positions[std::size_t(tri[0])];
    const Vector3d n = (holed.vertices.positions[std::size_t(tri[1])] - a).cross(holed.vertices.positions[std::size_t(tri[2])] - a);
    EXPECT_GT(n.dot(a), 0.0);
  }
}

TEST(FillHoles, TheLimitDecidesWhichHolesClose) {
  const TriangleMesh whole = test::icosphere_mesh(4, 1.0);
  const TriangleMesh holed = cut(cut(whole, Vector3d(0, 0, 1), 0.12), Vector3d(0, 0, -1), 0.45);  // small and large
  ASSERT_EQ(analyze_topology(holed).boundary_loops.size(), 2u);
  const double edge = mean_edge(holed);
  const MeshTopology t = analyze_topology(holed);
  const double small = t.boundary_loops.back().length / edge, large = t.boundary_loops.front().length / edge;
  ASSERT_LT(small, 20.0);
  ASSERT_GT(large, 20.0);
  TriangleMesh a = holed;
  const HoleFillStats sa = fill_holes(a);  // default 20: the small one only
  EXPECT_EQ(sa.holes_after, 1u);
  EXPECT_NEAR(analyze_topology(a).boundary_loops.front().length, t.boundary_loops.front().length, 1e-9);
  TriangleMesh b = holed;
  const HoleFillStats sb = fill_holes(b, {large + 5.0});  // the large one has too many corners (> 64) or closes
  EXPECT_LE(sb.holes_after, 1u);
  TriangleMesh c = holed;
  const HoleFillStats sc = fill_holes(c, {0.0});
  EXPECT_EQ(sc.holes_filled, 0u);
  EXPECT_EQ(c.triangles, holed.triangles);
}

TEST(FillHoles, ClosesAnInnerHoleOfAnOpenGridAndLeavesItsBorder) {
  TriangleMesh m = cut(grid(30), Vector3d(15, 15, 0), 1.6);
  ASSERT_EQ(analyze_topology(m).boundary_loops.size(), 2u);  // border (120 edges) and hole
  m.face_fields.add("id", m.triangles.size(), ScalarType::Int32);
  const HoleFillStats s = fill_holes(m);
  EXPECT_EQ(s.holes_filled, 1u);
  const MeshTopology after = analyze_topology(m);
  ASSERT_EQ(after.boundary_loops.size(), 1u);
  EXPECT_NEAR(after.boundary_loops.front().length, 120.0, 1e-9);
  EXPECT_EQ(after.non_manifold_vertices, 0u);
  for (const Triangle& t : m.triangles) {  // flat and facing +z
    const Vector3d n = (m.vertices.positions[std::size_t(t[1])] - m.vertices.positions[std::size_t(t[0])]).cross(m.vertices.positions[std::size_t(t[2])] - m.vertices.positions[std::size_t(t[0])]);
    EXPECT_GT(n.z(), 0.0);
  }
  EXPECT_TRUE(s.face_fields_dropped);
  EXPECT_TRUE(m.face_fields.empty());
}

TEST(FillHoles, SameResultAMillionMetresAway) {
  TriangleMesh m = cut(test::icosphere_mesh(4, 1.0), Vector3d(0, 0, 1), 0.15);
  // Jittered (seeded) so that no two fillings tie exactly, as on a scan.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(-0.005, 0.005);
  for (Vector3d& v : m.vertices.positions) v += Vector3d(jitter(rng), jitter(rng), jitter(rng));
  TriangleMesh far = m;
  const Vector3d shift(1e6, -3e6, 2e5);
  for (Vector3d& v : far.vertices.positions) v += shift;
  fill_holes(m);
  fill_holes(far);
  EXPECT_EQ(m.triangles, far.triangles);
}

TEST(FillHoles, RejectsBadParametersAndMeshes) {
  TriangleMesh m = test::icosphere_mesh(2);
  EXPECT_THROW(fill_holes(m, {-1.0}), UsageError);
  EXPECT_THROW(fill_holes(m, {std::nan("")}), UsageError);
  m.triangles.emplace_back(0, 1, int(m.vertices.positions.size()));
  EXPECT_THROW(fill_holes(m), InputError);
}

}  // namespace
}  // namespace pointsurf
