// SPDX-License-Identifier: GPL-3.0-or-later
// The triangle hierarchy against brute force: closest points on random soups and random
// queries, the feature of the closest point, winding numbers of closed and open meshes, box
// overlaps, and the error paths.
#include "pointsurf/evaluate/triangle_bvh.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/mesh_shapes.h"

namespace pointsurf {
namespace {

TEST(TriangleBvh, ClosestPointAgreesWithBruteForceOnRandomSoups) {
  for (const std::size_t count : {1u, 7u, 300u, 3000u}) {
    const TriangleMesh soup = test::random_soup(count, 11 + count);
    const TriangleBvh bvh(soup);
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> u(-0.5, 1.5);
    for (int q = 0; q < 300; ++q) {
      const Vector3d p(u(rng), u(rng), u(rng));
      const ClosestPoint c = bvh.closest(p);
      ASSERT_TRUE(c.found());
      const double expected = test::brute_force_squared_distance(p, soup);
      EXPECT_NEAR(c.squared_distance, expected, 1e-12 * (1.0 + expected)) << "soup of " << count << ", query " << q;
      // The point returned lies on the triangle returned, at the distance returned.
      EXPECT_NEAR((c.point - p).squaredNorm(), c.squared_distance, 1e-12);
      TriangleMesh hit;
      hit.vertices.positions.assign(soup.vertices.positions.begin() + 3 * c.triangle, soup.vertices.positions.begin() + 3 * c.triangle + 3);
      hit.triangles = {Triangle(0, 1, 2)};
      const double on_triangle = test::brute_force_squared_distance(c.point, hit);
      EXPECT_LT(on_triangle, 1e-20);
    }
  }
}

// The oracle: every triangle through the same exact test, about the hierarchy's origin, the
// smallest squared distance and among equal ones the smallest index.
ClosestPoint brute_force_closest(const TriangleBvh& bvh, const Vector3d& query) {
  ClosestPoint best;
  const Vector3d p = query - bvh.origin();
  for (std::size_t t = 0; t < bvh.triangle_count(); ++t) {
    ClosestPoint c = closest_point_on_triangle(p, bvh.corner(t, 0), bvh.corner(t, 1), bvh.corner(t, 2));
    if (!best.found() || c.squared_distance < best.squared_distance) {
      c.triangle = static_cast<int>(t);
      best = c;
    }
  }
  return best;
}

// Float boxes, float lower bounds of the triangles and the previous query's triangle as a hint
// change nothing: the same squared distance to the last bit and the same triangle, on meshes
// with ties (grids: queries over shared vertices and edges), thin and degenerate triangles, and
// 1e6 offsets; queries near the surface, far from it and on it.
TEST(TriangleBvh, ClosestIsExactlyTheBruteForceAnswerWithTiesToTheSmallestIndex) {
  std::vector<TriangleMesh> meshes = {test::grid_mesh(12), test::grid_cube(6), test::random_soup(2000, 41), test::icosphere_mesh(3)};
  TriangleMesh slivers = test::random_soup(400, 43);
  for (std::size_t t = 0; t < slivers.triangles.size(); t += 3) {  // collinear, repeated and nearly collinear corners
    const std::size_t v = 3 * t;
    slivers.vertices.positions[v + 2] = slivers.vertices.positions[v] + (t % 2 == 0 ? 2.0 : 1e-9) * (slivers.vertices.positions[v + 1] - slivers.vertices.positions[v]);
    if (t % 6 == 0) slivers.vertices.positions[v + 1] = slivers.vertices.positions[v];
  }
  meshes.push_back(slivers);
  TriangleMesh far = test::grid_cube(5, 3.0);
  for (Vector3d& v : far.vertices.positions) v += Vector3d(1e6, -2e6, 5e5);
  meshes.push_back(far);
  std::mt19937_64 rng(29);
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const TriangleBvh bvh(meshes[m]);
    const BoundingBox box = bounding_box(meshes[m].vertices.positions);
    const Vector3d centre = box.center(), half = 0.5 * (box.max - box.min) + Vector3d::Constant(1e-3);
    std::uniform_real_distribution<double> u(-1.6, 1.6);
    std::uniform_int_distribution<std::size_t> pick(0, meshes[m].vertices.positions.size() - 1);
    int hint = -1;
    for (int q = 0; q < 400; ++q) {
      Vector3d p;
      if (q % 4 == 0) p = meshes[m].vertices.positions[pick(rng)];  // on a vertex: ties among its triangles
      else if (q % 4 == 1) p = meshes[m].vertices.positions[pick(rng)] + 1e-3 * Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(half);
      else p = centre + Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(half);
      if (m == 0 && q % 8 == 2) p.z() = 0.0;  // in the grid's plane
      const ClosestPoint expected = brute_force_closest(bvh, p);
      for (const ClosestPoint& c : {bvh.closest(p), bvh.closest_near(p, hint), bvh.closest_near(p, static_cast<int>(pick(rng) % bvh.triangle_count()))}) {
        ASSERT_TRUE(c.found());
        EXPECT_EQ(c.squared_distance, expected.squared_distance) << "mesh " << m << ", query " << q;
        EXPECT_EQ(c.triangle, expected.triangle) << "mesh " << m << ", query " << q;
        EXPECT_EQ(c.feature, expected.feature) << "mesh " << m << ", query " << q;
      }
      hint = expected.triangle;
    }
  }
}

TEST(TriangleBvh, MaxDistanceLimitsTheSearch) {
  const TriangleMesh cube = test::cube_mesh();
  const TriangleBvh bvh(cube);
  EXPECT_FALSE(bvh.closest(Vector3d(3, 0, 0), 1.5).found());
  const ClosestPoint c = bvh.closest(Vector3d(3, 0, 0), 2.5);
  ASSERT_TRUE(c.found());
  EXPECT_NEAR(std::sqrt(c.squared_distance), 2.0, 1e-15);
}

TEST(TriangleBvh, ClosestFeatureIsFaceEdgeOrVertex) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(closest_point_on_triangle(Vector3d(0.2, 0.2, 1), a, b, c).feature, TriangleFeature::Face);
  const ClosestPoint edge = closest_point_on_triangle(Vector3d(0.5, -1, 0.3), a, b, c);
  EXPECT_EQ(edge.feature, TriangleFeature::Edge);
  EXPECT_EQ(edge.local_index, 0);  // a -> b
  const ClosestPoint hyp = closest_point_on_triangle(Vector3d(1, 1, 0), a, b, c);
  EXPECT_EQ(hyp.feature, TriangleFeature::Edge);
  EXPECT_EQ(hyp.local_index, 1);   // b -> c
  const ClosestPoint vertex = closest_point_on_triangle(Vector3d(-1, -1, 0), a, b, c);
  EXPECT_EQ(vertex.feature, TriangleFeature::Vertex);
  EXPECT_EQ(vertex.local_index, 0);
  // A degenerate triangle (collinear corners) is answered as its segments.
  const ClosestPoint flat = closest_point_on_triangle(Vector3d(0.5, 1, 0), a, b, Vector3d(2, 0, 0));
  EXPECT_NEAR(flat.squared_distance, 1.0, 1e-15);
}

TEST(TriangleBvh, WindingNumberIsOneInsideZeroOutsideAndFractionalThroughAHole) {
  const TriangleMesh sphere = test::icosphere_mesh(3);
  const TriangleBvh bvh(sphere);
  EXPECT_NEAR(bvh.winding_number(Vector3d(0.1, 0.2, -0.3)), 1.0, 2e-2);
  EXPECT_NEAR(bvh.winding_number(Vector3d(0.0, 0.0, 0.97)), 1.0, 2e-2);
  EXPECT_NEAR(bvh.winding_number(Vector3d(2.0, 1.0, 0.0)), 0.0, 2e-2);
  EXPECT_NEAR(bvh.winding_number(Vector3d(0.0, 0.0, 1.02)), 0.0, 2e-2);
  // Exact summation (accuracy beyond every cluster) agrees with the hierarchical one.
  EXPECT_NEAR(bvh.winding_number(Vector3d(0.3, 0.3, 0.3), 1e9), 1.0, 1e-12);
  // The open box: from its centre the missing face subtends 1/6 of the sphere of directions.
  const TriangleBvh open(test::open_box_mesh());
  EXPECT_NEAR(open.winding_number(Vector3d::Zero(), 1e9), 5.0 / 6.0, 1e-12);
  EXPECT_NEAR(open.winding_number(Vector3d::Zero()), 5.0 / 6.0, 2e-2);
}

TEST(TriangleBvh, OverlappingVisitsExactlyTheTrianglesWhoseBoxesOverlap) {
  const TriangleMesh soup = test::random_soup(500, 3);
  const TriangleBvh bvh(soup);
  const Vector3d lo(0.2, 0.3, 0.1), hi(0.5, 0.6, 0.4);
  std::set<int> got;
  bvh.overlapping(lo, hi, [&](int t) { got.insert(t); });
  std::set<int> expected;
  for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
    Vector3d tlo = soup.vertices.positions[3 * t], thi = tlo;
    for (int c = 1; c < 3; ++c) {
      tlo = tlo.cwiseMin(soup.vertices.positions[3 * t + std::size_t(c)]);
      thi = thi.cwiseMax(soup.vertices.positions[3 * t + std::size_t(c)]);
    }
    if ((tlo.array() <= hi.array()).all() && (thi.array() >= lo.array()).all()) expected.insert(static_cast<int>(t));
  }
  EXPECT_EQ(got, expected);
  EXPECT_FALSE(expected.empty());
}

TEST(TriangleBvh, BadIndicesThrowAndAnEmptyMeshFindsNothing) {
  TriangleMesh bad = test::cube_mesh();
  bad.triangles[4][1] = 8;
  try {
    const TriangleBvh bvh(bad);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 4: vertex index 8 out of range"), std::string::npos) << e.what();
  }
  const TriangleBvh empty(TriangleMesh{});
  EXPECT_FALSE(empty.closest(Vector3d::Zero()).found());
  EXPECT_EQ(empty.winding_number(Vector3d::Zero()), 0.0);
}

// The build reports growing fractions up to 1 (subtrees of 4096 triangles as they finish), the
// same hierarchy with or without a listener, and stops with CancelledError when told to.
TEST(TriangleBvh, BuildReportsProgressAndCanBeCancelled) {
  const TriangleMesh mesh = test::icosphere_mesh(6);  // 81920 triangles
  std::vector<double> fractions;
  const TriangleBvh heard(mesh, [&](double f) {
    fractions.push_back(f);
    return true;
  });
  ASSERT_GE(fractions.size(), 10u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  const TriangleBvh plain(mesh);
  for (const Vector3d& p : {Vector3d(0.3, 0.2, 0.1), Vector3d(2, -1, 0.5), Vector3d(0, 0, 1.01)}) {
    EXPECT_EQ(heard.closest(p).triangle, plain.closest(p).triangle);
    EXPECT_EQ(heard.closest(p).squared_distance, plain.closest(p).squared_distance);
  }
  std::size_t calls = 0;
  EXPECT_THROW(TriangleBvh(mesh, [&](double) { return ++calls < 3; }), CancelledError);
}

}  // namespace
}  // namespace pointsurf
