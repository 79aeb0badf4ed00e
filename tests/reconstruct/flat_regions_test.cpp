// SPDX-License-Identifier: GPL-3.0-or-later
// Flat regions on meshes whose regions are known by construction: a cube's six sides, one
// plane, a sphere cut into caps; invariance under face permutation and a 1e6 m shift.
#include "pointsurf/reconstruct/flat_regions.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/mesh_shapes.h"

namespace pointsurf {
namespace {

Vector3d face_normal(const TriangleMesh& m, std::size_t f) {
  const Triangle& t = m.triangles[f];
  return (m.vertices.positions[std::size_t(t[1])] - m.vertices.positions[std::size_t(t[0])]).cross(m.vertices.positions[std::size_t(t[2])] - m.vertices.positions[std::size_t(t[0])]).normalized();
}

double angle_deg(const Vector3d& a, const Vector3d& b) { return std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180.0 / std::numbers::pi; }

// Labels numbered by smallest face index: the first occurrences run 0, 1, 2, ...
void expect_numbered_by_first_face(const FlatRegionResult& r) {
  int next = 0;
  for (const int label : r.region) {
    ASSERT_LE(label, next);
    if (label == next) ++next;
  }
  EXPECT_EQ(static_cast<std::size_t>(next), r.regions);
}

TEST(FlatRegions, CubeHasSixRegionsOneSideEach) {
  const TriangleMesh cube = test::grid_cube(4);
  const FlatRegionResult r = label_flat_regions(cube);
  ASSERT_EQ(r.region.size(), cube.triangle_count());
  EXPECT_EQ(r.regions, 6u);
  EXPECT_EQ(r.largest_region, 32u);  // 4 x 4 squares of two triangles
  // Same region exactly when the normals are the same (the side is the region).
  for (std::size_t a = 0; a < cube.triangle_count(); ++a)
    for (std::size_t b = a + 1; b < cube.triangle_count(); ++b)
      EXPECT_EQ(r.region[a] == r.region[b], face_normal(cube, a).dot(face_normal(cube, b)) > 0.99) << a << " " << b;
  expect_numbered_by_first_face(r);
  // A threshold above the cube's 90 degrees joins everything (with the seed cone off).
  FlatRegionParams loose;
  loose.max_normal_angle_deg = 91.0;
  loose.max_seed_angle_deg = 180.0;
  EXPECT_EQ(label_flat_regions(cube, loose).regions, 1u);
}

TEST(FlatRegions, JitteredPlaneIsOneRegion) {
  TriangleMesh plane;
  const int n = 20;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) plane.vertices.positions.emplace_back(i + jitter(rng), j + jitter(rng), 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = a + n + 1;
      plane.triangles.insert(plane.triangles.end(), {Triangle(a, b, b + 1), Triangle(a, b + 1, a + 1)});
    }
  const FlatRegionResult r = label_flat_regions(plane);
  EXPECT_EQ(r.regions, 1u);
  EXPECT_EQ(r.largest_region, plane.triangle_count());
  EXPECT_TRUE(std::all_of(r.region.begin(), r.region.end(), [](int l) { return l == 0; }));
}

TEST(FlatRegions, SphereIsCutIntoCapsNoWiderThanTheSeedCone) {
  const TriangleMesh sphere = test::icosphere_mesh(3);  // 1280 faces, about 8 degrees between neighbours
  const FlatRegionParams params;
  const FlatRegionResult r = label_flat_regions(sphere, params);
  // Each region lies within max_seed_angle_deg of its seed: at most a cap of that half-angle,
  // a share (1 - cos 30) / 2 of the sphere, so at least 15 regions; and no two of its faces
  // differ by more than twice the cone.
  EXPECT_GE(r.regions, 15u);
  EXPECT_LT(r.regions, sphere.triangle_count() / 4);  // regions, not single faces
  std::map<int, std::vector<std::size_t>> members;
  for (std::size_t f = 0; f < r.region.size(); ++f) members[r.region[f]].push_back(f);
  EXPECT_EQ(members.size(), r.regions);
  for (const auto& [label, faces] : members)
    for (const std::size_t a : faces)
      for (const std::size_t b : faces) ASSERT_LE(angle_deg(face_normal(sphere, a), face_normal(sphere, b)), 2 * params.max_seed_angle_deg + 1e-9);
  expect_numbered_by_first_face(r);
  // Without the seed cone the small angles between neighbours chain the whole sphere.
  FlatRegionParams chained;
  chained.max_seed_angle_deg = 180.0;
  EXPECT_EQ(label_flat_regions(sphere, chained).regions, 1u);
}

// The partition as a set of face sets, independent of the labels' names.
std::set<std::set<std::size_t>> partition(const std::vector<int>& region, const std::vector<std::size_t>& original) {
  std::map<int, std::set<std::size_t>> groups;
  for (std::size_t f = 0; f < region.size(); ++f) groups[region[f]].insert(original[f]);
  std::set<std::set<std::size_t>> out;
  for (auto& [label, faces] : groups) out.insert(faces);
  return out;
}

TEST(FlatRegions, PermutedFacesGiveTheSamePartition) {
  const TriangleMesh sphere = test::icosphere_mesh(3);
  std::vector<std::size_t> identity(sphere.triangle_count());
  std::iota(identity.begin(), identity.end(), 0);
  std::vector<std::size_t> order = identity;
  std::mt19937_64 rng(11);
  std::shuffle(order.begin(), order.end(), rng);
  TriangleMesh permuted = sphere;
  for (std::size_t f = 0; f < order.size(); ++f) permuted.triangles[f] = sphere.triangles[order[f]];
  const FlatRegionResult a = label_flat_regions(sphere);
  const FlatRegionResult b = label_flat_regions(permuted);
  EXPECT_EQ(a.regions, b.regions);
  EXPECT_EQ(partition(a.region, identity), partition(b.region, order));
  expect_numbered_by_first_face(b);
}

TEST(FlatRegions, ShiftBy1e6GivesTheSameLabels) {
  // Vertices on a grid of 2^-20 so that the shift itself is exact: what is tested is that
  // nothing downstream depends on the distance from the origin.
  TriangleMesh sphere = test::icosphere_mesh(3, 2.0);
  for (Vector3d& p : sphere.vertices.positions) p = (p * 1048576.0).array().round().matrix() / 1048576.0;
  TriangleMesh shifted = sphere;
  for (Vector3d& p : shifted.vertices.positions) p += Vector3d(1e6, -2e6, 5e5);
  const FlatRegionResult a = label_flat_regions(sphere);
  const FlatRegionResult b = label_flat_regions(shifted);
  EXPECT_GE(a.regions, 15u);
  EXPECT_EQ(a.region, b.region);
  const TriangleMesh cube = test::grid_cube(3, 0.5);
  TriangleMesh far_cube = cube;
  for (Vector3d& p : far_cube.vertices.positions) p += Vector3d(4.5e6, 5.5e6, 120.0);
  EXPECT_EQ(label_flat_regions(cube).region, label_flat_regions(far_cube).region);
  EXPECT_EQ(label_flat_regions(far_cube).regions, 6u);
}

TEST(FlatRegions, BoundaryNonManifoldAndDegenerateFacesSeparate) {
  // Three coplanar triangles on one edge (0, 1): a non-manifold edge joins none of them; a
  // fourth face of zero area stays alone; a face sharing a manifold edge with the first joins.
  TriangleMesh m;
  m.vertices.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0.5, 1, 0), Vector3d(0.5, 2, 0), Vector3d(0.5, 3, 0),
                Vector3d(1.5, 1, 0), Vector3d(2, 0, 0)};
  m.triangles = {Triangle(0, 1, 2), Triangle(0, 1, 3), Triangle(0, 1, 4), Triangle(1, 5, 2), Triangle(1, 6, 6)};
  const FlatRegionResult r = label_flat_regions(m);
  EXPECT_EQ(r.region, (std::vector<int>{0, 1, 2, 0, 3}));
  EXPECT_EQ(r.regions, 4u);
  EXPECT_EQ(r.largest_region, 2u);
  // Opposite orientation across a manifold edge: normals 180 degrees apart, kept apart.
  TriangleMesh flipped;
  flipped.vertices.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(1, 1, 0)};
  flipped.triangles = {Triangle(0, 1, 2), Triangle(1, 2, 3)};
  EXPECT_EQ(label_flat_regions(flipped).regions, 2u);
  EXPECT_EQ(label_flat_regions(TriangleMesh{}).regions, 0u);
}

TEST(FlatRegions, ReportsMonotoneProgressAndCancels) {
  const TriangleMesh sphere = test::icosphere_mesh(4);
  std::vector<double> fractions;
  const FlatRegionResult r = label_flat_regions(sphere, {}, [&](double f) {
    fractions.push_back(f);
    return true;
  });
  EXPECT_EQ(r.regions, label_flat_regions(sphere).regions);
  ASSERT_GE(fractions.size(), 4u);
  for (std::size_t i = 1; i < fractions.size(); ++i) EXPECT_GE(fractions[i], fractions[i - 1]);
  EXPECT_GE(fractions.back(), 0.95);
  EXPECT_LE(fractions.back(), 1.0);
  EXPECT_THROW(label_flat_regions(sphere, {}, [](double) { return false; }), CancelledError);
}

TEST(FlatRegions, BadParametersAndMeshesThrow) {
  const TriangleMesh cube = test::grid_cube(1);
  FlatRegionParams p;
  p.max_normal_angle_deg = 0.0;
  test::expect_error<UsageError>([&] { label_flat_regions(cube, p); }, "label_flat_regions: max_normal_angle_deg must be in (0, 180], got 0");
  p = {};
  p.max_seed_angle_deg = 200.0;
  test::expect_error<UsageError>([&] { label_flat_regions(cube, p); }, "max_seed_angle_deg must be in (0, 180], got 200");
  TriangleMesh bad = cube;
  bad.triangles[3][1] = 99;
  test::expect_error<InputError>([&] { label_flat_regions(bad); }, "triangle 3: vertex index 99 out of range");
}

}  // namespace
}  // namespace pointsurf
