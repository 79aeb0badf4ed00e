// SPDX-License-Identifier: GPL-3.0-or-later
// Each acceptance rule of the region-growing triangulation (SPEC C10: minimum and maximum
// inner angle, maximum edge length, maximum dihedral angle, normal angle) on a cloud where
// the rule changes the result: the strict setting leaves no triangle that breaks the rule as
// measured on the output, where the loose setting has some.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/reconstruct/triangulate.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

double angle_between(const Vector3d& a, const Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

// The three inner angles of a triangle, degrees.
std::array<double, 3> inner_angles(const TriangleMesh& m, const Triangle& t) {
  std::array<double, 3> out{};
  for (int c = 0; c < 3; ++c) {
    const Vector3d& p = m.vertices.positions[std::size_t(t[c])];
    out[std::size_t(c)] = angle_between(m.vertices.positions[std::size_t(t[(c + 1) % 3])] - p, m.vertices.positions[std::size_t(t[(c + 2) % 3])] - p);
  }
  return out;
}

Vector3d face_normal(const TriangleMesh& m, const Triangle& t) {
  return (m.vertices.positions[std::size_t(t[1])] - m.vertices.positions[std::size_t(t[0])]).cross(m.vertices.positions[std::size_t(t[2])] - m.vertices.positions[std::size_t(t[0])]).normalized();
}

std::size_t count_if_triangle(const TriangleMesh& m, auto&& predicate) {
  return static_cast<std::size_t>(std::count_if(m.triangles.begin(), m.triangles.end(), predicate));
}

// Angles between the normals of triangles sharing an edge, one per interior edge.
std::vector<double> dihedral_angles(const TriangleMesh& m) {
  struct Half {
    int lo, hi, face;
    bool operator<(const Half& o) const { return lo != o.lo ? lo < o.lo : hi < o.hi; }
  };
  std::vector<Half> halves;
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = m.triangles[f][c], b = m.triangles[f][(c + 1) % 3];
      halves.push_back({std::min(a, b), std::max(a, b), static_cast<int>(f)});
    }
  std::sort(halves.begin(), halves.end());
  std::vector<double> out;
  for (std::size_t i = 0; i + 1 < halves.size(); ++i)
    if (!(halves[i] < halves[i + 1]) && !(halves[i + 1] < halves[i]))
      out.push_back(angle_between(face_normal(m, m.triangles[std::size_t(halves[i].face)]), face_normal(m, m.triangles[std::size_t(halves[i + 1].face)])));
  return out;
}

// Uniform random points on the unit square, normals +z: its Delaunay triangulation has
// triangles of every shape, skinny and obtuse ones among them.
PointCloud random_square(std::size_t n, std::uint64_t seed) {
  PointCloud cloud;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    cloud.positions.emplace_back(u(rng), u(rng), 0.0);
    cloud.normals.emplace_back(0.0, 0.0, 1.0);
  }
  return cloud;
}

// Rules only: no closing of fronts or holes afterwards, which do not apply them.
TriangulateParams rules_only() {
  TriangulateParams p;
  p.max_front_angle_deg = 0.0;
  p.max_hole_perimeter_in_spacings = 0.0;
  return p;
}

double smallest_angle(const TriangleMesh& m, const Triangle& t) {
  const auto a = inner_angles(m, t);
  return *std::min_element(a.begin(), a.end());
}
double largest_angle(const TriangleMesh& m, const Triangle& t) {
  const auto a = inner_angles(m, t);
  return *std::max_element(a.begin(), a.end());
}

// How many triangles of the mesh built with `loose`, and of the one built with `strict`, have
// `breaks(mesh, triangle)`.
template <typename Breaks>
std::array<std::size_t, 2> breaking(const PointCloud& cloud, const TriangulateParams& loose, const TriangulateParams& strict, Breaks breaks) {
  std::array<std::size_t, 2> out{};
  for (int s = 0; s < 2; ++s) {
    const TriangleMesh m = reconstruct_region_growing(cloud, s == 0 ? loose : strict).mesh;
    EXPECT_GT(m.triangle_count(), 500u);  // both are meshes of the square, not empty
    out[std::size_t(s)] = count_if_triangle(m, [&](const Triangle& t) { return breaks(m, t); });
  }
  return out;
}

TEST(TriangulateRules, MinimumInnerAngle) {
  TriangulateParams loose = rules_only(), strict = rules_only();
  loose.min_angle_deg = 0.0;
  strict.min_angle_deg = 20.0;
  const auto [a, b] = breaking(random_square(800, 21), loose, strict, [](const TriangleMesh& m, const Triangle& t) { return smallest_angle(m, t) < 20.0; });
  EXPECT_GT(a, 20u);  // measured: 354 of 1503 triangles
  EXPECT_EQ(b, 0u);
}

TEST(TriangulateRules, MaximumInnerAngle) {
  TriangulateParams loose = rules_only(), strict = rules_only();
  loose.max_angle_deg = 180.0;
  strict.max_angle_deg = 100.0;
  const auto [a, b] = breaking(random_square(800, 22), loose, strict, [](const TriangleMesh& m, const Triangle& t) { return largest_angle(m, t) > 100.0; });
  EXPECT_GT(a, 20u);  // measured: 509 of 1489 triangles
  EXPECT_EQ(b, 0u);
}

double longest_edge(const TriangleMesh& m) {
  double longest = 0.0;
  for (const Triangle& t : m.triangles)
    for (int c = 0; c < 3; ++c) longest = std::max(longest, (m.vertices.positions[std::size_t(t[c])] - m.vertices.positions[std::size_t(t[(c + 1) % 3])]).norm());
  return longest;
}

TEST(TriangulateRules, MaximumEdgeLength) {
  // Two grids of spacing 0.1 with a gap of 0.25 between them: the default radius (3 local
  // spacings, 0.3) bridges it, a radius of 0.2 does not.
  PointCloud cloud;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      const double x = 0.1 * i + (i >= 10 ? 0.15 : 0.0);
      cloud.positions.emplace_back(x, 0.1 * j + 0.01 * ((i * 7 + j * 3) % 5), 0.0);
      cloud.normals.emplace_back(0.0, 0.0, 1.0);
    }
  const TriangulateResult a = reconstruct_region_growing(cloud, rules_only());
  TriangulateParams strict = rules_only();
  strict.radius = Length::cloud(0.2);
  const TriangulateResult b = reconstruct_region_growing(cloud, strict);
  EXPECT_GT(longest_edge(a.mesh), 0.25);
  EXPECT_EQ(a.topology.components, 1u);
  EXPECT_LE(longest_edge(b.mesh), 0.2);
  EXPECT_EQ(b.topology.components, 2u);
}

TEST(TriangulateRules, MaximumDihedralAngle) {
  const PointCloud cloud = test::sample_cube(4000, 1.0, 3);
  TriangulateParams loose = rules_only();
  loose.max_dihedral_deg = 135.0;
  TriangulateParams strict = rules_only();
  strict.max_dihedral_deg = 60.0;
  const TriangulateResult a = reconstruct_region_growing(cloud, loose);
  const TriangulateResult b = reconstruct_region_growing(cloud, strict);
  const std::vector<double> da = dihedral_angles(a.mesh), db = dihedral_angles(b.mesh);
  const double max_a = *std::max_element(da.begin(), da.end()), max_b = *std::max_element(db.begin(), db.end());
  // The loose rule bridges the cube's 90-degree edges (93.6 degrees measured where a strip meets a
  // side), the strict one stops at 60 and leaves more of the edges open.
  EXPECT_GT(max_a, 85.0);
  EXPECT_LE(max_b, 60.0 + 1e-9);
  EXPECT_GT(b.topology.boundary_edges, a.topology.boundary_edges);
}

TEST(TriangulateRules, NormalAngleBetweenNeighbours) {
  // One flat sheet whose points carry normals tilted by 40 degrees for x > 0.5 (a bad normal
  // estimate): with the default 120 degrees triangles join points of both halves, with 30 none
  // joins points whose normals differ by more than 30 degrees.
  PointCloud cloud = random_square(800, 23);
  const Vector3d tilted(std::sin(40.0 * std::numbers::pi / 180.0), 0.0, std::cos(40.0 * std::numbers::pi / 180.0));
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (cloud.positions[i].x() > 0.5) cloud.normals[i] = tilted;
  // Triangles whose corners' normals differ by more than 30 degrees (those across x = 0.5).
  const auto mixed = [&](const TriangleMesh& m) {
    return count_if_triangle(m, [&](const Triangle& t) {
      double worst = 0.0;
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, angle_between(cloud.normals[std::size_t(t[c])], cloud.normals[std::size_t(t[(c + 1) % 3])]));
      return worst > 30.0;
    });
  };
  const TriangulateResult a = reconstruct_region_growing(cloud, rules_only());
  TriangulateParams strict = rules_only();
  strict.max_normal_angle_deg = 30.0;
  const TriangulateResult b = reconstruct_region_growing(cloud, strict);
  EXPECT_GT(mixed(a.mesh), 20u);
  EXPECT_EQ(mixed(b.mesh), 0u);
  // Each half on its own is still triangulated.
  EXPECT_GT(b.mesh.triangle_count(), a.mesh.triangle_count() / 2);
}

}  // namespace
}  // namespace pointsurf
