// SPDX-License-Identifier: GPL-3.0-or-later
// Area-uniform sampling (seeded, proportional to area, on the triangles) and Chamfer and
// Hausdorff distances between clouds and meshes whose answers are known.
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/evaluate/triangle_bvh.h"

#include <cmath>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/mesh_shapes.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(SurfaceDistance, SamplingIsSeededAreaUniformAndOnTheSurface) {
  TriangleMesh two;
  two.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 5}, {3, 0, 5}, {0, 3, 5}};
  two.triangles = {Triangle(0, 1, 2), Triangle(3, 4, 5)};  // areas 1/2 and 9/2
  const std::vector<Vector3d> s = sample_mesh_surface(two, 20000, 7);
  ASSERT_EQ(s.size(), 20000u);
  std::size_t upper = 0;
  for (const Vector3d& p : s) {
    upper += p.z() > 2.5;
    const double scale = p.z() > 2.5 ? 3.0 : 1.0;
    EXPECT_GE(p.x(), -1e-12);
    EXPECT_GE(p.y(), -1e-12);
    EXPECT_LE(p.x() + p.y(), scale + 1e-12);
  }
  EXPECT_NEAR(static_cast<double>(upper) / 20000.0, 0.9, 0.01);
  EXPECT_EQ(sample_mesh_surface(two, 10, 7), sample_mesh_surface(two, 10, 7));
  EXPECT_NE(sample_mesh_surface(two, 10, 7), sample_mesh_surface(two, 10, 8));
  EXPECT_TRUE(sample_mesh_surface(TriangleMesh{}, 10).empty());
}

TEST(SurfaceDistance, ShiftedCloudsAreTheShiftApart) {
  std::vector<Vector3d> a, b;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      a.emplace_back(i, j, 0.0);
      b.emplace_back(i, j, 0.25);
    }
  const SurfaceDistanceResult r = surface_distance({a, {}}, {b, {}});
  EXPECT_NEAR(r.chamfer, 0.25, 1e-12);
  EXPECT_NEAR(r.hausdorff, 0.25, 1e-12);
  EXPECT_EQ(r.a_to_b.count, 100u);
  EXPECT_EQ(r.samples_a, 0u);
}

TEST(SurfaceDistance, CloudAgainstAMeshIsExactOrSampled) {
  const TriangleMesh grid = test::grid_mesh(4);
  std::vector<Vector3d> above;
  for (int i = 0; i < 50; ++i) above.emplace_back(-0.8 + 0.032 * i, 0.1, 0.2);
  const SurfaceView cloud{above, {}}, mesh{grid.vertices.positions, grid.triangles};
  const SurfaceDistanceResult exact = surface_distance(cloud, mesh, {.exact = true, .samples = 5000});
  EXPECT_NEAR(exact.a_to_b.max, 0.2, 1e-12);
  EXPECT_NEAR(exact.a_to_b.mean, 0.2, 1e-12);
  EXPECT_EQ(exact.samples_b, 5000u);  // the mesh side was sampled to measure back from it
  // Back from the whole square to the short row of points: at least the far corner's distance.
  EXPECT_GT(exact.b_to_a.max, 1.0);
  EXPECT_NEAR(exact.hausdorff, exact.b_to_a.max, 1e-15);
  const SurfaceDistanceResult sampled = surface_distance(cloud, mesh, {.exact = false, .samples = 20000});
  EXPECT_GE(sampled.a_to_b.mean, 0.2 - 1e-12);
  EXPECT_LT(sampled.a_to_b.mean, 0.21);
  EXPECT_THROW(surface_distance({{}, {}}, mesh), InputError);
}

// A coarse icosphere inscribed in a sphere scan: every vertex touches the scan, but the flat
// triangles cut chords under it, so the points measured against them are all outside
// (positive), as the evaluate stage signs them. Each vertex must show that positive offset,
// where the deviation of its nearest point (about 0: the vertex lies on the scan) showed none.
TEST(SurfaceDistance, VertexDeviationShowsWhatThePointsAcrossItsTrianglesMeasure) {
  const Vector3d at(4e5, -3e6, 50.0);
  const TriangleMesh mesh = test::icosphere_mesh(1, 1.0, at);
  const PointCloud scan = test::sample_sphere(20000, 1.0, at);
  const std::vector<double> d = nearest_surface_distances(scan.positions, SurfaceView{mesh.vertices.positions, mesh.triangles});
  for (double v : d) ASSERT_GE(v, 0.0);
  const std::vector<double> at_vertex = vertex_deviation_from_points(mesh, scan.positions, d);
  ASSERT_EQ(at_vertex.size(), mesh.vertices.positions.size());
  // Brute force: the signed RMS of the points whose closest triangle touches the vertex.
  std::vector<double> sum_sq(at_vertex.size(), 0.0);
  std::vector<int> count(at_vertex.size(), 0);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    std::size_t best = 0;
    double best_d = 1e300;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Triangle& tri = mesh.triangles[t];
      const ClosestPoint c = closest_point_on_triangle(scan.positions[i], mesh.vertices.positions[std::size_t(tri[0])],
                                                       mesh.vertices.positions[std::size_t(tri[1])], mesh.vertices.positions[std::size_t(tri[2])]);
      if (c.squared_distance < best_d) best_d = c.squared_distance, best = t;
    }
    for (int c = 0; c < 3; ++c) {
      sum_sq[std::size_t(mesh.triangles[best][c])] += d[i] * d[i];
      ++count[std::size_t(mesh.triangles[best][c])];
    }
  }
  for (std::size_t v = 0; v < at_vertex.size(); ++v) {
    ASSERT_GT(count[v], 0);
    // Within 1 %: a point above a shared edge is as close to either triangle, and the two
    // searches may pick different ones.
    EXPECT_NEAR(at_vertex[v], std::sqrt(sum_sq[v] / count[v]), 1e-2 * at_vertex[v]) << "vertex " << v;
    EXPECT_GT(at_vertex[v], 0.02) << "vertex " << v;  // chords of a 42-vertex icosphere sit ~0.05 deep at their centres
  }
  // Negative deviations give a negative value; a vertex no point is measured against gets NaN.
  std::vector<double> negative(d.size());
  for (std::size_t i = 0; i < d.size(); ++i) negative[i] = -d[i];
  EXPECT_LT(vertex_deviation_from_points(mesh, scan.positions, negative)[0], 0.0);
  TriangleMesh extra = mesh;
  extra.vertices.positions.push_back(at + Vector3d(5, 5, 5));
  extra.vertices.positions.push_back(at + Vector3d(5, 6, 5));
  extra.vertices.positions.push_back(at + Vector3d(6, 5, 5));
  const int n = static_cast<int>(mesh.vertices.positions.size());
  extra.triangles.emplace_back(n, n + 1, n + 2);
  const std::vector<double> far = vertex_deviation_from_points(extra, scan.positions, d);
  EXPECT_TRUE(std::isnan(far[std::size_t(n)]));
  EXPECT_THROW(vertex_deviation_from_points(mesh, scan.positions, std::vector<double>(3, 0.0)), InputError);
}

}  // namespace
}  // namespace pointsurf
