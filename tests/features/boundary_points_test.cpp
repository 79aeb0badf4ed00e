// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/features/boundary_points.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

// A jittered n x n grid of spacing 1 in a tilted plane, without normals.
PointCloud tilted_grid(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  const Vector3d u = Vector3d(1, 0, 0.3).normalized(), v = Vector3d(0, 1, -0.2).normalized();
  PointCloud c;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) c.positions.push_back((i + jitter(rng)) * u + (j + jitter(rng)) * v + Vector3d(5e5, 4e6, 100.0));
  return c;
}

TEST(BoundaryPoints, AGridsRimIsTheBoundaryAndItsInteriorIsNot) {
  const int n = 40;
  const PointCloud grid = tilted_grid(n, 1);
  const BoundaryResult r = detect_boundary_points(grid);
  std::size_t rim_missed = 0, inner_flagged = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool rim = i == 0 || j == 0 || i == n - 1 || j == n - 1;
      const bool inner = i >= 2 && j >= 2 && i <= n - 3 && j <= n - 3;
      const bool flagged = r.boundary[std::size_t(j * n + i)] != 0;
      if (rim && !flagged) ++rim_missed;
      if (inner && flagged) ++inner_flagged;
    }
  EXPECT_EQ(rim_missed, 0u);     // every one of the 156 rim points (gap about 180 degrees)
  EXPECT_EQ(inner_flagged, 0u);  // none of the 1296 points two rows in
  EXPECT_GT(r.gap_deg[0], 180.0);  // a corner: about 270
  EXPECT_LT(r.gap_deg[std::size_t(20 * n + 20)], 90.0);
}

TEST(BoundaryPoints, AClosedSphereHasNoneAndAHoleHasItsRim) {
  const PointCloud sphere = test::sample_sphere(8000, 1.0, Vector3d::Zero(), 4);
  // Random samples leave an interior point a wide empty sector now and then (0.5 % measured).
  EXPECT_LT(detect_boundary_points(sphere).count, 8000u / 100);
  // A cap cut away (z > 0.8): the points next to the cut are the boundary.
  PointCloud cut;
  for (std::size_t i = 0; i < sphere.size(); ++i)
    if (sphere.positions[i].z() < 0.8) cut.positions.push_back(sphere.positions[i]);
  const BoundaryResult r = detect_boundary_points(cut);
  const double spacing = std::sqrt(4.0 * 3.14159265358979 / 8000.0);
  std::size_t near_cut = 0, far_flagged = 0;
  for (std::size_t i = 0; i < cut.size(); ++i) {
    if (!r.boundary[i]) continue;
    if (cut.positions[i].z() > 0.8 - 2.5 * spacing) ++near_cut;
    else ++far_flagged;
  }
  EXPECT_GT(near_cut, 30u);  // the rim circle (radius 0.6) holds about 3.8 / spacing = 95 points
  EXPECT_LT(far_flagged, cut.size() / 100);
}

TEST(BoundaryPoints, UsesGivenNormalsAndIgnoresInputOrder) {
  PointCloud grid = tilted_grid(30, 2);
  const BoundaryResult pca = detect_boundary_points(grid);
  grid.normals.assign(grid.size(), Vector3d(1, 0, 0.3).normalized().cross(Vector3d(0, 1, -0.2).normalized()).normalized());
  const BoundaryResult given = detect_boundary_points(grid);
  EXPECT_EQ(pca.boundary, given.boundary);
  std::vector<std::size_t> perm(grid.size());
  std::iota(perm.begin(), perm.end(), std::size_t{0});
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(9));
  const BoundaryResult shuffled = detect_boundary_points(grid.select(perm));
  for (std::size_t i = 0; i < perm.size(); ++i) EXPECT_EQ(shuffled.boundary[i], given.boundary[perm[i]]);
}

TEST(BoundaryPoints, RejectsBadParameters) {
  const PointCloud grid = tilted_grid(5, 3);
  EXPECT_THROW(detect_boundary_points(grid, {3, 90.0}), UsageError);
  EXPECT_THROW(detect_boundary_points(grid, {16, 0.0}), UsageError);
  EXPECT_THROW(detect_boundary_points(grid, {16, 360.0}), UsageError);
}

}  // namespace
}  // namespace pointsurf
