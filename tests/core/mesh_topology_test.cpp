// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/mesh_topology.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace pointsurf {
namespace {

TriangleMesh tetrahedron() {
  TriangleMesh mesh;
  mesh.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

// A (rows x cols) vertex grid on [0,1]^2; wrap_u / wrap_v glue opposite sides (torus when both).
TriangleMesh grid(int rows, int cols, bool wrap_u, bool wrap_v) {
  TriangleMesh mesh;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      if (wrap_u && wrap_v) {
        const double u = 2 * std::numbers::pi * i / rows, v = 2 * std::numbers::pi * j / cols;
        mesh.vertices.positions.push_back({(2 + std::cos(v)) * std::cos(u), (2 + std::cos(v)) * std::sin(u), std::sin(v)});
      } else {
        mesh.vertices.positions.push_back({static_cast<double>(j) / (cols - 1), static_cast<double>(i) / (rows - 1), 0.0});
      }
    }
  const int cell_rows = wrap_u ? rows : rows - 1, cell_cols = wrap_v ? cols : cols - 1;
  auto id = [&](int i, int j) { return (i % rows) * cols + (j % cols); };
  for (int i = 0; i < cell_rows; ++i)
    for (int j = 0; j < cell_cols; ++j) {
      mesh.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  return mesh;
}

TEST(MeshTopology, TetrahedronIsAWatertightSphere) {
  const MeshTopology t = analyze_topology(tetrahedron());
  EXPECT_EQ(t.vertices, 4u);
  EXPECT_EQ(t.edges, 6u);
  EXPECT_EQ(t.triangles, 4u);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.genus(), 0);
  EXPECT_EQ(t.components, 1u);
  EXPECT_TRUE(t.boundary_loops.empty());
}

TEST(MeshTopology, TorusHasGenusOne) {
  const MeshTopology t = analyze_topology(grid(12, 8, true, true));
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_EQ(t.genus(), 1);
}

TEST(MeshTopology, OpenPatchHasOneBoundaryLoopWithItsPerimeter) {
  const MeshTopology t = analyze_topology(grid(5, 5, false, false));
  EXPECT_TRUE(t.edge_manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_FALSE(t.closed());
  EXPECT_EQ(t.boundary_edges, 16u);
  ASSERT_EQ(t.boundary_loops.size(), 1u);
  EXPECT_EQ(t.boundary_loops[0].vertices.size(), 16u);
  EXPECT_NEAR(t.boundary_loops[0].length, 4.0, 1e-12);
  EXPECT_EQ(t.euler_characteristic, 1);
  EXPECT_EQ(t.genus(), 0);  // a disc: (2 - 1 - 1) / 2
  EXPECT_EQ(t.non_manifold_vertices, 0u);
}

TEST(MeshTopology, CylinderHasTwoLoops) {
  const MeshTopology t = analyze_topology(grid(6, 10, false, true));  // wrapped in one direction only
  EXPECT_EQ(t.boundary_loops.size(), 2u);
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_EQ(t.genus(), 0);  // an annulus: (2 - 0 - 2) / 2
}

TEST(MeshTopology, HoleInAClosedSurfaceIsOneLoop) {
  TriangleMesh mesh = tetrahedron();
  mesh.triangles.pop_back();
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_EQ(t.boundary_edges, 3u);
  ASSERT_EQ(t.boundary_loops.size(), 1u);
  EXPECT_NEAR(t.boundary_loops[0].length, 3 * std::sqrt(2.0), 1e-12);
}

TEST(MeshTopology, FlippedTriangleIsInconsistent) {
  TriangleMesh mesh = tetrahedron();
  std::swap(mesh.triangles[3][0], mesh.triangles[3][1]);
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_EQ(t.inconsistent_edges, 3u);
  EXPECT_FALSE(t.oriented());
  EXPECT_FALSE(t.watertight());
  EXPECT_EQ(t.genus(), -1);  // not orientable as given
}

TEST(MeshTopology, ThreeTrianglesOnOneEdgeAreNonManifold) {
  TriangleMesh mesh;
  mesh.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_EQ(t.non_manifold_edges, 1u);
  EXPECT_FALSE(t.edge_manifold());
}

TEST(MeshTopology, BowtieVertexAndComponentsAndDegenerates) {
  TriangleMesh mesh;
  mesh.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}, {5, 5, 5}, {6, 5, 5}};
  mesh.triangles = {{0, 1, 2}, {0, 3, 4}, {5, 6, 6}};
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_EQ(t.non_manifold_vertices, 1u);  // vertex 0 joins two separate fans
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.degenerate_triangles, 1u);
  EXPECT_EQ(t.isolated_vertices, 2u);
  EXPECT_EQ(t.triangles, 2u);
}

TEST(MeshTopology, EmptyMesh) {
  const MeshTopology t = analyze_topology(TriangleMesh{});
  EXPECT_EQ(t.triangles, 0u);
  EXPECT_FALSE(t.watertight());
  EXPECT_EQ(t.components, 0u);
}

}  // namespace
}  // namespace pointsurf
