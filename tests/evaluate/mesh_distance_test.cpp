// SPDX-License-Identifier: GPL-3.0-or-later
// Signed point-to-mesh distances checked against answers known by construction: a plane, a
// cube (the analytic box distance) and a sphere mesh (convex: brute force outside, the nearest
// face plane inside), to 1e-9 of the diagonal; the sign by pseudo-normals and by the winding
// number on closed, open and self-intersecting meshes; invariance under a 1e6 m shift; errors.
#include "pointsurf/evaluate/mesh_distance.h"

#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/triangle_bvh.h"
#include "support/mesh_shapes.h"

namespace pointsurf {
namespace {

std::vector<Vector3d> random_points(std::size_t n, double lo, double hi, std::uint64_t seed, const Vector3d& shift = Vector3d::Zero()) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<Vector3d> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(shift + Vector3d(u(rng), u(rng), u(rng)));
  return out;
}

// The signed distance to a convex mesh centred at `center`: outside by brute force, inside
// minus the distance to the nearest face plane.
double convex_signed_distance(const Vector3d& p, const TriangleMesh& mesh) {
  double plane = -std::numeric_limits<double>::infinity();
  for (const Triangle& t : mesh.triangles) {
    const Vector3d& a = mesh.vertices.positions[std::size_t(t[0])];
    const Vector3d n = (mesh.vertices.positions[std::size_t(t[1])] - a).cross(mesh.vertices.positions[std::size_t(t[2])] - a).normalized();
    plane = std::max(plane, n.dot(p - a));
  }
  if (plane > 0.0) return std::sqrt(test::brute_force_squared_distance(p, mesh));
  return plane;
}

TEST(MeshDistance, PlaneGivesHeightWithItsSign) {
  const TriangleMesh grid = test::grid_mesh(8);
  std::vector<Vector3d> points;
  std::vector<double> expected;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> xy(-0.9, 0.9), z(-0.5, 0.5);
  for (int i = 0; i < 500; ++i) {
    points.emplace_back(xy(rng), xy(rng), z(rng));
    expected.push_back(points.back().z());
  }
  const MeshDistanceResult r = mesh_distances(points, grid);
  EXPECT_EQ(r.sign_used, DistanceSign::PseudoNormal);  // open, manifold, oriented
  const double diagonal = std::sqrt(8.0);
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_NEAR(r.distances[i], expected[i], 1e-9 * diagonal) << i;
}

TEST(MeshDistance, CubeMatchesTheAnalyticBoxDistanceInsideAndOutside) {
  const TriangleMesh cube = test::cube_mesh();
  const std::vector<Vector3d> points = random_points(3000, -3.0, 3.0, 5);
  const MeshDistanceResult r = mesh_distances(points, cube);
  EXPECT_EQ(r.sign_used, DistanceSign::PseudoNormal);
  EXPECT_EQ(r.self_intersections, 0u);
  const double diagonal = std::sqrt(12.0);
  std::size_t inside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double expected = test::box_signed_distance(points[i], 1.0);
    EXPECT_NEAR(r.distances[i], expected, 1e-9 * diagonal) << points[i].transpose();
    inside += expected < 0.0;
  }
  EXPECT_GT(inside, 50u);
  // The winding number gives the same signs on a watertight mesh.
  const MeshDistanceResult w = mesh_distances(points, cube, {.sign = DistanceSign::WindingNumber});
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_NEAR(w.distances[i], r.distances[i], 1e-9 * diagonal) << i;
}

TEST(MeshDistance, SphereMeshIsExactAndSignedOnBothSides) {
  const TriangleMesh sphere = test::icosphere_mesh(2);
  std::vector<Vector3d> points = random_points(1500, -1.6, 1.6, 9);
  // And points very near the surface, on both sides of a face, an edge and a vertex.
  for (const double d : {1e-3, -1e-3, 1e-7, -1e-7}) {
    points.push_back(sphere.vertices.positions[5] * (1.0 + d));
    points.push_back((sphere.vertices.positions[std::size_t(sphere.triangles[3][0])] + sphere.vertices.positions[std::size_t(sphere.triangles[3][1])]) * 0.5 * (1.0 + d));
  }
  const MeshDistanceResult r = mesh_distances(points, sphere);
  const double diagonal = 2.0 * std::sqrt(3.0);
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_NEAR(r.distances[i], convex_signed_distance(points[i], sphere), 1e-9 * diagonal) << i;
}

// A caller's hierarchy and topology give the same answer as the ones built inside.
TEST(MeshDistance, AKnownHierarchyAndTopologyGiveTheSameDistances) {
  const TriangleMesh sphere = test::icosphere_mesh(3);
  const std::vector<Vector3d> points = random_points(500, -1.5, 1.5, 17);
  const TriangleBvh bvh(sphere);
  const MeshTopology topology = analyze_topology(sphere);
  const MeshDistanceResult own = mesh_distances(points, sphere), given = mesh_distances(points, sphere, {}, &bvh, {}, &topology);
  EXPECT_EQ(given.sign_used, DistanceSign::PseudoNormal);
  EXPECT_EQ(given.sign_used, own.sign_used);
  EXPECT_EQ(given.distances, own.distances);
}

TEST(MeshDistance, ShiftBy1e6MetresChangesNothing) {
  const Vector3d shift(1.0e6, -2.0e6, 3.0e5);
  const TriangleMesh sphere = test::icosphere_mesh(2), shifted = test::icosphere_mesh(2, 1.0, shift);
  const std::vector<Vector3d> points = random_points(800, -1.5, 1.5, 13);
  std::vector<Vector3d> moved;
  for (const Vector3d& p : points) moved.push_back(p + shift);
  const MeshDistanceResult a = mesh_distances(points, sphere), b = mesh_distances(moved, shifted);
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_NEAR(a.distances[i], b.distances[i], 1e-9 * 2.0 * std::sqrt(3.0)) << i;
}

TEST(MeshDistance, WindingNumberSignsAnOpenBoxAndOverlappingClosedPieces) {
  // The open box: its pseudo-normal sign is right near the walls; the winding number is right
  // everywhere inside, also below the missing lid.
  const TriangleMesh box = test::open_box_mesh();
  const std::vector<Vector3d> inside = {{0, 0, 0}, {0.5, -0.5, 0.2}, {0, 0, 0.8}}, outside = {{0, 0, -1.5}, {2, 0, 0}, {0.5, 0.5, -1.2}};
  const MeshDistanceResult in = mesh_distances(inside, box, {.sign = DistanceSign::WindingNumber});
  for (const double d : in.distances) EXPECT_LT(d, 0.0);
  const MeshDistanceResult out = mesh_distances(outside, box, {.sign = DistanceSign::WindingNumber});
  for (const double d : out.distances) EXPECT_GT(d, 0.0);

  // Two interpenetrating cubes: closed and manifold, but self-intersecting, so Auto takes the
  // winding number; a point inside the first cube next to a wall of the second that lies inside
  // the first is inside.
  const TriangleMesh two = test::join_meshes(test::cube_mesh(1.0), test::cube_mesh(1.0, Vector3d(1.0, 0.3, 0.2)));
  const std::vector<Vector3d> p = {{-0.1, 0.0, 0.0}, {-0.5, -0.5, -0.5}, {1.5, 0.3, 0.2}, {3.0, 0.0, 0.0}};
  const MeshDistanceResult r = mesh_distances(p, two);
  EXPECT_EQ(r.sign_used, DistanceSign::WindingNumber);
  EXPECT_GT(r.self_intersections, 0u);
  EXPECT_FALSE(r.warnings.empty());
  EXPECT_NEAR(r.distances[0], -0.1, 1e-12);  // nearest is the second cube's wall x = 0
  EXPECT_LT(r.distances[1], 0.0);
  EXPECT_LT(r.distances[2], 0.0);
  EXPECT_NEAR(r.distances[3], 1.0, 1e-12);
}

TEST(MeshDistance, InconsistentOrientationGivesUnsignedDistancesWithAWarning) {
  TriangleMesh cube = test::cube_mesh();
  std::swap(cube.triangles[0][1], cube.triangles[0][2]);
  const std::vector<Vector3d> p = {{0, 0, 0}, {0, 0, 2}};
  const MeshDistanceResult r = mesh_distances(p, cube, {.sign = DistanceSign::Auto, .max_crack_share = 0.0});
  EXPECT_EQ(r.sign_used, DistanceSign::Unsigned);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings.front().find("unsigned"), std::string::npos);
  EXPECT_NEAR(r.distances[0], 1.0, 1e-12);
  EXPECT_NEAR(r.distances[1], 1.0, 1e-12);
}

TEST(MeshDistance, PseudoNormalsOfACubeCornerPointOutward) {
  const PseudoNormals n = pseudo_normals(test::cube_mesh());
  for (std::size_t v = 0; v < 8; ++v) {
    const Vector3d corner = test::cube_mesh().vertices.positions[v];
    EXPECT_GT(n.vertex[v].normalized().dot(corner.normalized()), 0.99) << v;
  }
  ASSERT_EQ(n.across.size(), 36u);
  for (std::size_t t = 0; t < 12; ++t)
    for (int i = 0; i < 3; ++i) {
      EXPECT_GE(n.across[3 * t + std::size_t(i)], 0);  // closed: every edge has a face across
      EXPECT_GT(n.edge(t, i).norm(), 0.9);
    }
}

TEST(MeshDistance, BadInputIsNamed) {
  const std::vector<Vector3d> p = {{0, 0, 0}};
  TriangleMesh empty;
  empty.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  try {
    mesh_distances(p, empty);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no faces"), std::string::npos) << e.what();
  }
  TriangleMesh nan = test::cube_mesh();
  nan.vertices.positions[3].x() = std::numeric_limits<double>::quiet_NaN();
  try {
    mesh_distances(p, nan);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 3"), std::string::npos) << e.what();
  }
  const std::vector<Vector3d> bad = {{0, 0, 0}, {std::numeric_limits<double>::infinity(), 0, 0}};
  EXPECT_THROW(mesh_distances(bad, test::cube_mesh()), InputError);
  EXPECT_THROW(mesh_distances(p, test::cube_mesh(), {.max_distance = -1.0}), UsageError);
  // Beyond max_distance a point has no distance (infinite), not a wrong one.
  const std::vector<Vector3d> far = {{10, 0, 0}};
  EXPECT_TRUE(std::isinf(mesh_distances(far, test::cube_mesh(), {.max_distance = 2.0}).distances[0]));
}

}  // namespace
}  // namespace pointsurf
