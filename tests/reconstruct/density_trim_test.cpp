// SPDX-License-Identifier: GPL-3.0-or-later
#include "reconstruct/detail/density_trim.h"

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "support/mesh_shapes.h"

namespace pointsurf {
namespace {

using detail::trim_by_vertex_field;

double area(const TriangleMesh& m) {
  double a = 0.0;
  for (const Triangle& t : m.triangles)
    a += 0.5 * (m.vertices.positions[t[1]] - m.vertices.positions[t[0]]).cross(m.vertices.positions[t[2]] - m.vertices.positions[t[0]]).norm();
  return a;
}

/// A field that is a function of the position, plus a copy as a second field.
void set_field(TriangleMesh& m, const std::function<double(const Vector3d&)>& f) {
  ScalarField& d = m.vertices.fields.add("density", m.vertices.positions.size());
  ScalarField& x = m.vertices.fields.add("x", m.vertices.positions.size(), ScalarType::Float32);
  for (std::size_t i = 0; i < m.vertices.positions.size(); ++i) d.values[i] = f(m.vertices.positions[i]), x.values[i] = m.vertices.positions[i].x();
}

TEST(DensityTrim, LinearFieldCutsThePlaneExactlyAtTheLevel) {
  // density = x on [-1, 1]^2: the part x >= 0.3 is kept, cut exactly (a linear field
  // interpolates exactly), with one boundary loop and every field carried.
  TriangleMesh m = test::grid_mesh(20);
  set_field(m, [](const Vector3d& p) { return p.x(); });
  m.face_fields.add("label", m.triangles.size());
  for (std::size_t f = 0; f < m.triangles.size(); ++f) m.face_fields[0].values[f] = double(f);
  const std::size_t before = m.triangles.size();
  const auto r = trim_by_vertex_field(m, "density", 0.3, 0.0, 0);
  m.validate();
  EXPECT_NEAR(area(m), 2.0 * 0.7, 1e-12);
  for (const Vector3d& v : m.vertices.positions) EXPECT_GE(v.x(), 0.3 - 1e-12);
  const ScalarField& d = *m.vertices.fields.find("density");
  const ScalarField& x = *m.vertices.fields.find("x");
  for (std::size_t i = 0; i < m.vertices.positions.size(); ++i) {
    EXPECT_NEAR(d.values[i], m.vertices.positions[i].x(), 1e-12);
    EXPECT_NEAR(x.values[i], m.vertices.positions[i].x(), 1e-12);
  }
  EXPECT_GT(r.cut_triangles, 0u);
  EXPECT_EQ(r.removed_islands + r.filled_holes, 0u);
  EXPECT_LT(r.removed_triangles, before);
  const MeshTopology topo = analyze_topology(m);
  EXPECT_EQ(topo.boundary_loops.size(), 1u);
  EXPECT_EQ(topo.non_manifold_edges + topo.non_manifold_vertices + topo.inconsistent_edges, 0u);
  EXPECT_EQ(topo.isolated_vertices, 0u);
  EXPECT_EQ(m.face_fields[0].values.size(), m.triangles.size());
}

TEST(DensityTrim, SphereTrimmedByHeightIsAHemisphereWithOneLoop) {
  TriangleMesh m = test::icosphere_mesh(4);
  set_field(m, [](const Vector3d& p) { return p.z(); });
  trim_by_vertex_field(m, "density", 0.0, 0.001, 0);
  const MeshTopology topo = analyze_topology(m);
  EXPECT_EQ(topo.boundary_loops.size(), 1u);
  EXPECT_EQ(topo.components, 1u);
  EXPECT_EQ(topo.genus(), 0);
  EXPECT_EQ(topo.non_manifold_edges + topo.non_manifold_vertices + topo.inconsistent_edges, 0u);
  EXPECT_NEAR(area(m), 2.0 * M_PI, 0.02 * 2.0 * M_PI);
  for (int v : topo.boundary_loops[0].vertices) EXPECT_NEAR(m.vertices.positions[v].z(), 0.0, 1e-12);
}

TEST(DensityTrim, SmallIslandsGoAndSmallHolesAreFilled) {
  // Kept: x < 0.2, plus a small bump near (0.7, 0.7); removed: a small dip near (-0.6, -0.6).
  auto bump = [](const Vector3d& p, double cx, double cy) { return std::hypot(p.x() - cx, p.y() - cy) < 0.12; };
  auto f = [&](const Vector3d& p) {
    if (bump(p, 0.7, 0.7)) return 1.0;
    if (bump(p, -0.6, -0.6)) return -1.0;
    return p.x() < 0.2 ? 1.0 : -1.0;
  };
  TriangleMesh a = test::grid_mesh(40);
  set_field(a, f);
  TriangleMesh b = a;
  const auto kept_all = trim_by_vertex_field(a, "density", 0.0, 0.0, 0);
  EXPECT_EQ(analyze_topology(a).components, 2u);
  EXPECT_EQ(analyze_topology(a).boundary_loops.size(), 3u);  // outer rim, the hole, the island
  const auto r = trim_by_vertex_field(b, "density", 0.0, 0.02, 0);  // islands of ~0.045 < 0.08
  EXPECT_EQ(r.removed_islands, 1u);
  EXPECT_EQ(r.filled_holes, 1u);
  EXPECT_EQ(kept_all.cut_triangles, r.cut_triangles);
  const MeshTopology topo = analyze_topology(b);
  EXPECT_EQ(topo.components, 1u);
  EXPECT_EQ(topo.boundary_loops.size(), 1u);
  EXPECT_EQ(topo.genus(), 0);
  EXPECT_EQ(topo.non_manifold_edges + topo.non_manifold_vertices + topo.inconsistent_edges, 0u);
  for (const Vector3d& v : b.vertices.positions) EXPECT_LT(v.x(), 0.3);
}

TEST(DensityTrim, SmoothingAveragesTheNeighbours) {
  // One vertex at 10 in a field of 0: after one round it is the mean of its neighbours (0), and
  // each neighbour gets at most 2 x 10 / 8 (two edge incidences of at least eight), so nothing
  // reaches 3.
  TriangleMesh m = test::grid_mesh(10);
  set_field(m, [](const Vector3d& p) { return p.norm() < 1e-9 ? 10.0 : 0.0; });
  TriangleMesh unsmoothed = m;
  trim_by_vertex_field(unsmoothed, "density", 3.0, 0.0, 0);
  EXPECT_GT(unsmoothed.triangles.size(), 0u);
  trim_by_vertex_field(m, "density", 3.0, 0.0, 1);
  EXPECT_EQ(m.triangles.size(), 0u);
  EXPECT_EQ(m.vertices.positions.size(), 0u);
}

TEST(DensityTrim, RejectsAMissingFieldAndBadParameters) {
  TriangleMesh m = test::grid_mesh(2);
  EXPECT_THROW(trim_by_vertex_field(m, "density", 0.0), InputError);
  set_field(m, [](const Vector3d&) { return 0.0; });
  EXPECT_THROW(trim_by_vertex_field(m, "density", 0.0, -1.0), UsageError);
  EXPECT_THROW(trim_by_vertex_field(m, "density", 0.0, 0.1, -2), UsageError);
}

}  // namespace
}  // namespace pointsurf
