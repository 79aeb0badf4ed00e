// SPDX-License-Identifier: GPL-3.0-or-later
// Area-uniform sampling (seeded, proportional to area, on the triangles) and Chamfer and
// Hausdorff distances between clouds and meshes whose answers are known.
#include "pointsurf/evaluate/surface_distance.h"

#include <cmath>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/mesh_shapes.h"

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

}  // namespace
}  // namespace pointsurf
