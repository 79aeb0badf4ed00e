// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/reconstruct/ball_pivot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <set>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/distances.h"
#include "support/files.h"
#include "support/reconstruct_surface.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::expect_error;

// Hausdorff distance between the mesh surface and the true surface, both sampled densely: the
// true surface is given by a dense sample of the same shape (different seed).
double hausdorff_to(const ReconstructionResult& r, const PointCloud& truth) {
  const std::vector<Vector3d> on_mesh = test::sample_mesh_surface(r.mesh.vertices.positions, r.mesh.triangles, truth.size());
  return test::set_distances(on_mesh, truth.positions).hausdorff;
}

// Every triangle's counter-clockwise normal agrees with the normals of its vertices.
std::size_t flipped_triangles(const TriangleMesh& mesh) {
  std::size_t flipped = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vector3d n = (mesh.vertices.positions[t[1]] - mesh.vertices.positions[t[0]]).cross(mesh.vertices.positions[t[2]] - mesh.vertices.positions[t[0]]);
    const Vector3d vn = mesh.vertices.normals[t[0]] + mesh.vertices.normals[t[1]] + mesh.vertices.normals[t[2]];
    if (!(n.dot(vn) > 0.0)) ++flipped;
  }
  return flipped;
}

// The triangles as a set that ignores where each starts: every triangle rotated so that its
// smallest index comes first (the orientation stays), `to_original` mapping vertex indices to
// those of a reference cloud (empty: the identity).
using CanonicalTriangle = std::array<std::size_t, 3>;
std::set<CanonicalTriangle> canonical_triangles(const TriangleMesh& mesh, const std::vector<std::size_t>& to_original = {}) {
  std::set<CanonicalTriangle> out;
  for (const Triangle& tri : mesh.triangles) {
    CanonicalTriangle t{};
    for (int c = 0; c < 3; ++c) {
      const auto v = static_cast<std::size_t>(tri[c]);
      t[std::size_t(c)] = to_original.empty() ? v : to_original[v];
    }
    while (t[0] > t[1] || t[0] > t[2]) t = CanonicalTriangle{t[1], t[2], t[0]};
    out.insert(t);
  }
  return out;
}

// Share of the triangles of `a` that are also in `b`.
double shared_share(const std::set<CanonicalTriangle>& a, const std::set<CanonicalTriangle>& b) {
  std::size_t shared = 0;
  for (const CanonicalTriangle& t : a) shared += b.count(t);
  return a.empty() ? 1.0 : double(shared) / double(a.size());
}

void expect_closed_genus(const ReconstructionResult& r, long genus) {
  const MeshTopology& t = r.topology;
  EXPECT_TRUE(t.edge_manifold()) << t.non_manifold_edges << " non-manifold edges";
  EXPECT_TRUE(t.oriented()) << t.inconsistent_edges << " inconsistent edges";
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler_characteristic, 2 - 2 * genus);
  EXPECT_EQ(flipped_triangles(r.mesh), 0u);
}

TEST(BallPivot, SphereIsClosedGenusZeroWithinTwoSpacings) {
  const PointCloud cloud = test::sample_sphere(4000, 1.0);
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud);
  expect_closed_genus(r, 0);
  EXPECT_EQ(r.unused_points, 0u);
  ASSERT_EQ(r.mesh.vertex_count(), cloud.size());
  EXPECT_EQ(r.mesh.vertices.normals, cloud.normals);  // vertices are the points, normals kept
  EXPECT_GT(r.mean_spacing, 0.0);
  EXPECT_LE(hausdorff_to(r, test::sample_sphere(40000, 1.0, Vector3d::Zero(), 9)), 2.0 * r.mean_spacing);
}

TEST(BallPivot, TorusIsClosedGenusOne) {
  const PointCloud cloud = test::sample_torus(8000, 1.0, 0.35);
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud);
  expect_closed_genus(r, 1);
  EXPECT_LE(hausdorff_to(r, test::sample_torus(60000, 1.0, 0.35, 9)), 2.0 * r.mean_spacing);
}

TEST(BallPivot, CubeIsClosedAcrossSharpEdges) {
  const PointCloud cloud = test::sample_cube(6000, 1.0);
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud);
  expect_closed_genus(r, 0);
  EXPECT_LE(hausdorff_to(r, test::sample_cube(60000, 1.0, 9)), 2.0 * r.mean_spacing);
}

// The small-hole pass is what closes the last holes along the cube's edges; without it the
// pivoting alone leaves some (measured: 20 holes, 76 boundary edges on this sample).
TEST(BallPivot, SmallHolePassClosesTheHolesLeftAlongSharpEdges) {
  const PointCloud cloud = test::sample_cube(6000, 1.0);
  BallPivotParams open;
  open.max_hole_perimeter_in_spacings = 0.0;
  const ReconstructionResult pivoted = reconstruct_ball_pivoting(cloud, open);
  EXPECT_GT(pivoted.topology.boundary_edges, 0u);
  EXPECT_TRUE(pivoted.topology.edge_manifold());
  const ReconstructionResult closed = reconstruct_ball_pivoting(cloud);
  EXPECT_EQ(closed.topology.boundary_edges, 0u);
  EXPECT_GE(closed.mesh.triangle_count(), pivoted.mesh.triangle_count());
}

TEST(BallPivot, OpenPatchHasExactlyOneBoundaryLoop) {
  const PointCloud cloud = test::sample_plane(3000, 1.0);
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud);
  const MeshTopology& t = r.topology;
  EXPECT_TRUE(t.edge_manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_EQ(t.components, 1u);
  ASSERT_EQ(t.boundary_loops.size(), 1u);
  EXPECT_EQ(t.euler_characteristic, 1);  // a disc
  EXPECT_EQ(flipped_triangles(r.mesh), 0u);
  // The rim runs around the square: its perimeter is close to 8.
  EXPECT_GT(t.boundary_loops[0].length, 7.0);
  // An interpolating mesh ends at the outermost samples, up to a few spacings inside the true
  // square's edge, so the distances are one-sided: the mesh lies on the square (mesh -> square),
  // and covers the square shrunk by 2 mean spacings (shrunk square -> mesh). Measured: 0.019
  // and 0.018 against the limit 2 spacings = 0.036 (the symmetric Hausdorff to the whole square
  // is 0.055, at its corners; the mesh-to-square figure is the truth sample's own gaps).
  const double s = r.mean_spacing;
  const std::vector<Vector3d> on_mesh = test::sample_mesh_surface(r.mesh.vertices.positions, r.mesh.triangles, 40000);
  EXPECT_LE(test::max_nearest_distance(on_mesh, test::sample_plane(40000, 1.0, 9).positions), 2.0 * s);
  EXPECT_LE(test::max_nearest_distance(test::sample_plane(40000, 1.0 - 2.0 * s, 9).positions, on_mesh), 2.0 * s);
}

// Two sheets 3 spacings apart, each a patch of its own: no triangle may join them. Checked
// with the sheets facing the same way (stacked scans) and facing each other (a thin plate).
TEST(BallPivot, NeverBridgesParallelPlanesThreeSpacingsApart) {
  for (const bool facing : {false, true}) {
    PointCloud lower = test::sample_plane(2000, 1.0, 1);
    const double spacing = mean_spacing(lower.positions);
    PointCloud upper = test::sample_plane(2000, 1.0, 2);
    for (Vector3d& p : upper.positions) p.z() = 3.0 * spacing;
    if (facing)
      for (Vector3d& n : lower.normals) n = -n;
    PointCloud both = lower;
    both.append(upper);
    const ReconstructionResult r = reconstruct_ball_pivoting(both);
    std::size_t bridges = 0;
    for (const Triangle& t : r.mesh.triangles) {
      const bool a = t[0] < 2000, b = t[1] < 2000, c = t[2] < 2000;
      if (a != b || b != c) ++bridges;
    }
    EXPECT_EQ(bridges, 0u) << (facing ? "facing" : "stacked");
    EXPECT_EQ(r.topology.components, 2u) << (facing ? "facing" : "stacked");
    EXPECT_TRUE(r.topology.edge_manifold());
  }
}

TEST(BallPivot, DuplicatesAreLeftUnusedAndTheMeshStaysCorrect) {
  PointCloud cloud = test::sample_sphere(3000, 1.0);
  const PointCloud copy = cloud;
  cloud.append(copy);  // every point twice
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud);
  expect_closed_genus(r, 0);
  EXPECT_EQ(r.unused_points, 3000u);
  EXPECT_EQ(r.topology.degenerate_triangles, 0u);
}

TEST(BallPivot, AStackOfManyCopiesStaysCheapAndUnused) {
  // 20,000 copies of one sample: found by sorting (the radius queries of each copy would cost
  // the square of the stack), all but the first left unused, the sphere closed.
  PointCloud cloud = test::sample_sphere(3000, 1.0);
  cloud.append(cloud.select(std::vector<std::size_t>(20000, 11)));
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud);
  expect_closed_genus(r, 0);
  EXPECT_EQ(r.unused_points, 20000u);
}

TEST(BallPivot, AFirstCopyWithoutNormalLeavesTheNextCopyInUse) {
  // Near-duplicates: the first without a usable normal is skipped, so the second one stands in.
  PointCloud cloud = test::sample_sphere(3000, 1.0);
  const double spacing = mean_spacing(cloud.positions);
  cloud.positions.push_back(cloud.positions[0] + Vector3d::Constant(1e-9 * spacing));
  cloud.normals.push_back(cloud.normals[0]);
  cloud.normals[0] = Vector3d::Zero();
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud);
  expect_closed_genus(r, 0);
  EXPECT_EQ(r.unused_points, 1u);  // point 0 only
  bool last_used = false;
  for (const Triangle& t : r.mesh.triangles)
    for (int c = 0; c < 3; ++c) last_used |= std::size_t(t[c]) == cloud.size() - 1;
  EXPECT_TRUE(last_used);
}

TEST(BallPivot, ExplicitRadiiAreUsedAsGiven) {
  const PointCloud cloud = test::sample_sphere(3000, 1.0);
  BallPivotParams tiny;
  tiny.radii = {1e-6};  // far below the spacing: no ball can rest on three points
  const ReconstructionResult none = reconstruct_ball_pivoting(cloud, tiny);
  EXPECT_EQ(none.mesh.triangle_count(), 0u);
  EXPECT_EQ(none.unused_points, cloud.size());
  BallPivotParams explicit_radii;
  const double s = mean_spacing(cloud.positions);
  explicit_radii.radii = {6.0 * s, 1.5 * s, 3.0 * s};  // order does not matter
  const ReconstructionResult a = reconstruct_ball_pivoting(cloud, explicit_radii);
  const ReconstructionResult b = reconstruct_ball_pivoting(cloud);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
}

TEST(BallPivot, CollinearPointsGiveAnEmptyMesh) {
  PointCloud line;
  for (int i = 0; i < 50; ++i) {
    line.positions.emplace_back(0.1 * i, 0.0, 0.0);
    line.normals.emplace_back(0.0, 0.0, 1.0);
  }
  const ReconstructionResult r = reconstruct_ball_pivoting(line);
  EXPECT_EQ(r.mesh.triangle_count(), 0u);
  EXPECT_EQ(r.unused_points, 50u);
}

TEST(BallPivot, CoplanarGridIsTriangulatedCompletely) {
  // A regular grid: four co-circular points per cell, the degenerate case for the pivot angle.
  PointCloud grid;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      grid.positions.emplace_back(0.1 * i, 0.1 * j, 0.0);
      grid.normals.emplace_back(0.0, 0.0, 1.0);
    }
  const ReconstructionResult r = reconstruct_ball_pivoting(grid);
  EXPECT_EQ(r.mesh.triangle_count(), 2u * 29u * 29u);
  EXPECT_EQ(r.unused_points, 0u);
  EXPECT_TRUE(r.topology.edge_manifold());
  EXPECT_TRUE(r.topology.oriented());
  EXPECT_EQ(r.topology.boundary_loops.size(), 1u);
  EXPECT_EQ(flipped_triangles(r.mesh), 0u);
}

TEST(BallPivot, SameMeshAfterAMillionMetreShiftAndARotation) {
  const PointCloud cloud = test::sample_sphere(3000, 1.0);
  const ReconstructionResult base = reconstruct_ball_pivoting(cloud);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  PointCloud moved = cloud;
  for (std::size_t i = 0; i < moved.size(); ++i) {
    moved.positions[i] = rotation * moved.positions[i] + Vector3d(1e6, 2e6, 5e5);
    moved.normals[i] = rotation * moved.normals[i];
  }
  const ReconstructionResult r = reconstruct_ball_pivoting(moved);
  expect_closed_genus(r, 0);
  // Seeds follow the spatial order, which rotates with the cloud; on a generic sample no four
  // points are co-circular, so the empty-ball triangles are the same whatever the order.
  EXPECT_EQ(r.mesh.triangle_count(), base.mesh.triangle_count());
  EXPECT_EQ(shared_share(canonical_triangles(r.mesh), canonical_triangles(base.mesh)), 1.0);
  EXPECT_NEAR(r.mean_spacing, base.mean_spacing, 1e-6 * base.mean_spacing);
}

TEST(BallPivot, PermutedPointsGiveTheSameSurface) {
  const PointCloud cloud = test::sample_torus(5000, 1.0, 0.35);
  std::vector<std::size_t> perm(cloud.size());
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(5));
  const ReconstructionResult base = reconstruct_ball_pivoting(cloud);
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud.select(perm));
  expect_closed_genus(r, 1);
  EXPECT_EQ(r.mesh.triangle_count(), base.mesh.triangle_count());
  // The same triangles, vertex i of the permuted cloud being point perm[i].
  EXPECT_EQ(shared_share(canonical_triangles(r.mesh, perm), canonical_triangles(base.mesh)), 1.0);
}

TEST(BallPivot, ReusesAGivenTreeAndReportsProgress) {
  const PointCloud cloud = test::sample_sphere(2000, 1.0);
  const KdTree tree(cloud.positions);
  std::vector<double> fractions;
  const ReconstructionResult r = reconstruct_ball_pivoting(cloud, {}, &tree, [&](double f) {
    fractions.push_back(f);
    return true;
  });
  expect_closed_genus(r, 0);
  ASSERT_FALSE(fractions.empty());
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
}

TEST(BallPivot, CancelsWhenProgressSaysStop) {
  const PointCloud cloud = test::sample_sphere(20000, 1.0);
  EXPECT_THROW(reconstruct_ball_pivoting(cloud, {}, nullptr, [](double) { return false; }), CancelledError);
}

TEST(BallPivot, RejectsBadInput) {
  const PointCloud cloud = test::sample_sphere(100, 1.0);
  PointCloud two;
  two.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0)};
  two.normals = {Vector3d(0, 0, 1), Vector3d(0, 0, 1)};
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(two); }, "needs at least 3 points, got 2");
  PointCloud bare = cloud;
  bare.normals.clear();
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(bare); }, "the cloud has no normals");
  PointCloud short_normals = cloud;
  short_normals.normals.pop_back();
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(short_normals); }, "has 99 normals for 100 points");
  BallPivotParams p;
  p.radii = {0.1, -1.0};
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(cloud, p); }, "radii must be > 0 and finite, got -1");
  p = {};
  p.radii_in_spacings = {0.0};
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(cloud, p); }, "radii_in_spacings must be > 0 and finite, got 0");
  p = {};
  p.radii_in_spacings.clear();
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(cloud, p); }, "radii and radii_in_spacings are both empty");
  p = {};
  p.max_normal_angle_deg = 0.0;
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(cloud, p); }, "max_normal_angle_deg must be in (0, 180], got 0");
  p = {};
  p.max_mean_normal_angle_deg = 200.0;
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(cloud, p); }, "max_mean_normal_angle_deg must be in (0, 180], got 200");
  const KdTree other(two.positions);
  expect_error<UsageError>([&] { reconstruct_ball_pivoting(cloud, {}, &other); },
                           "the kd-tree holds 2 points but the cloud has 100");
  PointCloud nan = cloud;
  nan.positions[7].x() = std::nan("");
  expect_error<InputError>([&] { reconstruct_ball_pivoting(nan); }, "point 7 has a non-finite coordinate");
  PointCloud same;
  for (int i = 0; i < 5; ++i) {
    same.positions.emplace_back(1.0, 2.0, 3.0);
    same.normals.emplace_back(0.0, 0.0, 1.0);
  }
  expect_error<ComputeError>([&] { reconstruct_ball_pivoting(same); }, "all 5 points coincide");
}

}  // namespace
}  // namespace pointsurf
