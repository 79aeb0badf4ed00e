// SPDX-License-Identifier: GPL-3.0-or-later
// Every quality flag on meshes whose answer is known: a cube, an open box, a non-manifold
// bow-tie, a flipped face, two disjoint components, a self-intersecting pair, degenerate and
// duplicate faces; the angle and aspect-ratio distributions; a 1e6 m shift.
#include "pointsurf/evaluate/mesh_quality.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>
#include <limits>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/mesh_shapes.h"

namespace pointsurf {
namespace {

TEST(MeshQuality, CubeIsWatertightGenusZeroWithAreaAndVolume) {
  const MeshQuality q = analyze_mesh_quality(test::cube_mesh(1.0, Vector3d(1e6, -1e6, 5e5)));
  EXPECT_TRUE(q.edge_manifold);
  EXPECT_TRUE(q.vertex_manifold);
  EXPECT_TRUE(q.oriented);
  EXPECT_TRUE(q.closed);
  EXPECT_TRUE(q.watertight);
  EXPECT_EQ(q.genus, 0);
  EXPECT_EQ(q.topology.euler_characteristic, 2);
  EXPECT_EQ(q.topology.components, 1u);
  EXPECT_EQ(q.topology.triangles, 12u);
  EXPECT_EQ(q.topology.edges, 18u);
  EXPECT_EQ(q.degenerate_faces, 0u);
  EXPECT_EQ(q.duplicate_faces, 0u);
  EXPECT_EQ(q.self_intersections, 0u);
  EXPECT_NEAR(q.area, 24.0, 1e-9);
  ASSERT_TRUE(q.has_volume);
  EXPECT_NEAR(q.volume, 8.0, 1e-9);
  EXPECT_NEAR(q.angles_deg.min, 45.0, 1e-9);
  EXPECT_NEAR(q.angles_deg.max, 90.0, 1e-9);
  EXPECT_NEAR(q.angles_deg.mean, 60.0, 1e-9);
  ASSERT_EQ(q.angles_deg.counts.size(), 18u);
  EXPECT_EQ(q.angles_deg.counts[4], 24u);  // [40, 50): the 45 degree corners
  EXPECT_EQ(q.angles_deg.counts[9], 12u);  // [90, 100): the right angles
  // A right isosceles triangle: longest sqrt 2, perimeter 2 + sqrt 2, area 1/2.
  EXPECT_NEAR(q.aspect_ratios.max, std::sqrt(2.0) * (2.0 + std::sqrt(2.0)) / (2.0 * std::sqrt(3.0)), 1e-12);
}

TEST(MeshQuality, EquilateralTriangleHasAspectRatioOne) {
  TriangleMesh t;
  t.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, std::sqrt(3.0) / 2.0, 0}};
  t.triangles = {Triangle(0, 1, 2)};
  const MeshQuality q = analyze_mesh_quality(t);
  EXPECT_NEAR(q.aspect_ratios.min, 1.0, 1e-12);
  EXPECT_FALSE(q.closed);
  EXPECT_FALSE(q.has_volume);
  EXPECT_EQ(q.topology.boundary_loops.size(), 1u);
}

TEST(MeshQuality, OpenBoxHasOneLoopOfLengthEight) {
  const MeshQuality q = analyze_mesh_quality(test::open_box_mesh());
  EXPECT_FALSE(q.closed);
  EXPECT_FALSE(q.watertight);
  EXPECT_TRUE(q.edge_manifold);
  EXPECT_TRUE(q.oriented);
  ASSERT_EQ(q.topology.boundary_loops.size(), 1u);
  EXPECT_NEAR(q.topology.boundary_loops.front().length, 8.0, 1e-12);
  EXPECT_EQ(q.genus, 0);  // a disc
  EXPECT_FALSE(q.has_volume);
  EXPECT_NEAR(q.area, 20.0, 1e-12);
}

TEST(MeshQuality, BowTieIsVertexNonManifold) {
  TriangleMesh m;
  m.vertices.positions = {{0, 0, 0}, {1, 1, 0}, {1, -1, 0}, {-1, 1, 0}, {-1, -1, 0}};
  m.triangles = {Triangle(0, 2, 1), Triangle(0, 3, 4)};
  const MeshQuality q = analyze_mesh_quality(m);
  EXPECT_TRUE(q.edge_manifold);
  EXPECT_FALSE(q.vertex_manifold);
  EXPECT_EQ(q.topology.non_manifold_vertices, 1u);
  EXPECT_EQ(q.self_intersections, 0u);  // they share a vertex
  // Three triangles on one edge: edge non-manifold.
  TriangleMesh fin = test::cube_mesh();
  fin.vertices.positions.push_back(Vector3d(0, 0, 3));
  fin.triangles.push_back(Triangle(6, 7, 8));  // on the top edge from (-1,1,1) to (1,1,1)
  const MeshQuality f = analyze_mesh_quality(fin);
  EXPECT_FALSE(f.edge_manifold);
  EXPECT_EQ(f.topology.non_manifold_edges, 1u);
  EXPECT_FALSE(f.watertight);
}

TEST(MeshQuality, FlippedFaceBreaksOrientation) {
  TriangleMesh cube = test::cube_mesh();
  std::swap(cube.triangles[5][0], cube.triangles[5][1]);
  const MeshQuality q = analyze_mesh_quality(cube);
  EXPECT_FALSE(q.oriented);
  EXPECT_EQ(q.topology.inconsistent_edges, 3u);
  EXPECT_TRUE(q.closed);
  EXPECT_FALSE(q.watertight);
  EXPECT_FALSE(q.has_volume);
  EXPECT_EQ(q.genus, -1);
}

TEST(MeshQuality, TwoDisjointCubesAreTwoComponents) {
  const MeshQuality q = analyze_mesh_quality(test::join_meshes(test::cube_mesh(), test::cube_mesh(1.0, Vector3d(5, 0, 0))));
  EXPECT_EQ(q.topology.components, 2u);
  EXPECT_EQ(q.topology.euler_characteristic, 4);
  EXPECT_EQ(q.genus, -1);  // undefined for several components
  EXPECT_EQ(q.self_intersections, 0u);
  EXPECT_NEAR(q.volume, 16.0, 1e-12);
}

TEST(MeshQuality, CrossingPairIsOneSelfIntersection) {
  TriangleMesh m;
  m.vertices.positions = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {1.5, 1.5, 1}};
  m.triangles = {Triangle(0, 1, 2), Triangle(3, 4, 5)};
  EXPECT_EQ(analyze_mesh_quality(m).self_intersections, 1u);
  // Moved apart, they no longer cross.
  for (std::size_t v = 3; v < 6; ++v) m.vertices.positions[v].x() += 10.0;
  EXPECT_EQ(analyze_mesh_quality(m).self_intersections, 0u);
}

TEST(MeshQuality, DegenerateAndDuplicateFacesAreCounted) {
  TriangleMesh m = test::cube_mesh();
  m.triangles.push_back(m.triangles[0]);                       // duplicate
  m.triangles.push_back(Triangle(m.triangles[1][2], m.triangles[1][0], m.triangles[1][1]));  // same vertices, rotated
  m.triangles.push_back(Triangle(0, 0, 1));                    // repeated index
  m.vertices.positions.push_back(Vector3d(0, 0, 0));
  m.vertices.positions.push_back(Vector3d(1, 0, 0));
  m.vertices.positions.push_back(Vector3d(2, 0, 0));
  m.triangles.push_back(Triangle(8, 9, 10));                   // collinear
  const MeshQuality q = analyze_mesh_quality(m);
  EXPECT_EQ(q.duplicate_faces, 2u);
  EXPECT_EQ(q.degenerate_faces, 2u);
}

TEST(MeshQuality, BadInputIsNamed) {
  TriangleMesh m = test::cube_mesh();
  m.vertices.positions[2].y() = std::numeric_limits<double>::quiet_NaN();
  try {
    analyze_mesh_quality(m);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 2"), std::string::npos) << e.what();
  }
  m = test::cube_mesh();
  m.triangles[0][0] = -1;
  EXPECT_THROW(analyze_mesh_quality(m), InputError);
  const MeshQuality empty = analyze_mesh_quality(TriangleMesh{});
  EXPECT_FALSE(empty.watertight);
  EXPECT_EQ(empty.area, 0.0);
}

// Progress names the phases, grows to 1 through the self-intersection pass, changes nothing,
// and a false answer cancels.
TEST(MeshQuality, ReportsPhasesAndProgressAndCanBeCancelled) {
  const TriangleMesh mesh = test::icosphere_mesh(5);
  std::vector<std::string> phases;
  std::vector<double> fractions;
  PhasedProgress listener;
  listener.on_fraction = [&](double f) {
    fractions.push_back(f);
    return true;
  };
  listener.on_phase = [&](std::string_view name) { phases.emplace_back(name); };
  const MeshQuality heard = analyze_mesh_quality(mesh, nullptr, listener);
  EXPECT_EQ(phases, (std::vector<std::string>{"topology", "geometry", "self-intersections"}));
  ASSERT_GE(fractions.size(), 3u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  const MeshQuality plain = analyze_mesh_quality(mesh);
  EXPECT_EQ(heard.self_intersections, plain.self_intersections);
  EXPECT_EQ(heard.genus, 0);
  EXPECT_EQ(heard.area, plain.area);
  EXPECT_THROW(analyze_mesh_quality(mesh, nullptr, [](double f) { return f < 0.5; }), CancelledError);
}

}  // namespace
}  // namespace pointsurf
