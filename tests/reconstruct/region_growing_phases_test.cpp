// SPDX-License-Identifier: GPL-3.0-or-later
// The phases of reconstruct_region_growing (reconstruct/detail/region_growing.h), each run alone
// on small planar clouds with normals +z and, where a phase needs them, hand-made candidates or a
// hand-made selection.
#include "reconstruct/detail/region_growing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace pointsurf::detail {
namespace {

using V3 = std::array<std::uint32_t, 3>;

PointCloud planar(const std::vector<Vector3d>& pts) {
  PointCloud c;
  c.positions = pts;
  c.normals.assign(pts.size(), Vector3d::UnitZ());
  return c;
}

std::vector<Vector3d> grid(int side) {
  std::vector<Vector3d> pts;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) pts.emplace_back(x, y, 0);
  return pts;
}

// The cloud, its tree and the phase object over them (the object keeps references).
struct Fixture {
  PointCloud cloud;
  TriangulateParams params;
  KdTree tree;
  ProgressCallback progress;
  RegionGrowing g;
  Fixture(PointCloud c, const TriangulateParams& p = {})
      : cloud(std::move(c)), params(p), tree(cloud.positions), g(cloud, params, tree, progress) {}
  // The per-point phases, which every later one reads.
  void measure() {
    g.measure_points();
    g.widen_scan_lines();
  }
};

GrowthCandidate candidate(V3 v, float min_angle_deg = 30.0f, std::uint8_t votes = 1) {
  return GrowthCandidate{v, min_angle_deg, votes};
}

void add(Selection& sel, const PointCloud& cloud, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  const auto& p = cloud.positions;
  sel.add(a, b, c, (p[b] - p[a]).cross(p[c] - p[a]).normalized());
}

TEST(RegionGrowingPhases, MeasurePointsFindsSpacingDuplicatesAndMissingNormals) {
  // A 4 x 4 unit grid; point 0 without a normal, a copy of point 5 appended.
  std::vector<Vector3d> pts = grid(4);
  pts.push_back(pts[5]);
  PointCloud cloud = planar(pts);
  cloud.normals[0] = Vector3d::Zero();
  cloud.normals[16] = 2.0 * Vector3d::UnitZ();
  Fixture f(cloud);
  f.g.measure_points();
  const RegionGrowing& g = f.g;
  EXPECT_EQ(g.out.duplicate_points, 1u);
  EXPECT_EQ(g.usable[0], 0);
  EXPECT_EQ(g.normals[0], Vector3d::Zero());
  EXPECT_EQ(g.usable[5], 1);
  EXPECT_EQ(g.usable[16], 0);
  EXPECT_EQ(g.normals[16], Vector3d::UnitZ());  // unit
  // Inner points: four neighbours at 1 (the copy skipped); a corner: 1, 1, sqrt 2.
  EXPECT_EQ(g.local_spacing[5], 1.0);
  EXPECT_EQ(g.local_spacing[10], 1.0);
  EXPECT_DOUBLE_EQ(g.local_spacing[15], (2.0 + std::sqrt(2.0)) / 3.0);
  for (std::uint32_t j : g.nearest[10]) EXPECT_EQ((pts[j] - pts[10]).norm(), 1.0);
  EXPECT_EQ(g.line_like[5], 0);  // neighbours all around
}

TEST(RegionGrowingPhases, ScanLinePointsReachFourTimesFartherUnlessTheRadiusIsExplicit) {
  // Two lines of 10 points, 10 apart: each point's neighbours lie on its own line, on both
  // sides but at the two ends.
  std::vector<Vector3d> pts;
  for (int line = 0; line < 2; ++line)
    for (int x = 0; x < 10; ++x) pts.emplace_back(x, 10 * line, 0);
  Fixture f(planar(pts));
  f.measure();
  const RegionGrowing& g = f.g;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const bool end = i % 10 == 0 || i % 10 == 9;
    EXPECT_EQ(g.line_like[i], end ? 0 : 1) << i;
    EXPECT_EQ(g.on_line[i], end ? 0 : 1) << i;
    EXPECT_DOUBLE_EQ(g.radius_of[i], (end ? 1.0 : 4.0) * 3.0 * g.local_spacing[i]) << i;
  }
  TriangulateParams explicit_radius;
  explicit_radius.radius = Length::cloud(2.0);
  Fixture h(planar(pts), explicit_radius);
  h.measure();
  EXPECT_EQ(std::count(h.g.on_line.begin(), h.g.on_line.end(), 1), 0);
  EXPECT_EQ(h.g.radius_of, std::vector<double>(pts.size(), 2.0));
}

TEST(RegionGrowingPhases, EveryUmbrellaOfATriangleProposesIt) {
  // Three points: each one's umbrella is the triangle, counter-clockwise about +z.
  Fixture f(planar({{0, 0, 0}, {1, 0, 0}, {0.5, 0.8, 0}}));
  f.measure();
  f.g.propose_umbrellas();
  ASSERT_EQ(f.g.candidates.size(), 3u);
  for (const GrowthCandidate& c : f.g.candidates) {
    EXPECT_EQ(c.v, (V3{0, 1, 2}));
    EXPECT_EQ(c.votes, 1);
  }
  f.g.merge_candidates();
  ASSERT_EQ(f.g.candidates.size(), 1u);
  EXPECT_EQ(f.g.candidates[0].votes, 3);
  EXPECT_EQ(f.g.out.candidate_triangles, 1u);
}

TEST(RegionGrowingPhases, MergeCountsVotesAndSortsBestFirst) {
  Fixture f(planar(grid(3)));
  f.g.candidates = {candidate({0, 1, 2}, 30.0f), candidate({0, 2, 3}, 50.0f), candidate({1, 3, 2}, 10.0f),
                    candidate({0, 1, 2}, 30.0f), candidate({4, 5, 6}, 40.0f), candidate({1, 3, 2}, 10.0f),
                    candidate({4, 5, 6}, 40.0f), candidate({1, 3, 2}, 10.0f)};
  f.g.merge_candidates();
  ASSERT_EQ(f.g.candidates.size(), 4u);
  EXPECT_EQ(f.g.out.candidate_triangles, 4u);
  // Most votes first, then the larger smallest angle.
  const std::vector<std::pair<V3, int>> expected{{{1, 3, 2}, 3}, {{4, 5, 6}, 2}, {{0, 1, 2}, 2}, {{0, 2, 3}, 1}};
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(f.g.candidates[i].v, expected[i].first) << i;
    EXPECT_EQ(f.g.candidates[i].votes, expected[i].second) << i;
  }
}

TEST(RegionGrowingPhases, EdgeIndexFilesEachDirectedEdgeUnderItsFirstVertex) {
  // A unit square split along 0-2: six directed edges, two leaving 0 and 2, one leaving 1 and 3.
  Fixture f(planar({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  f.g.candidates = {candidate({0, 1, 2}), candidate({0, 2, 3})};
  f.g.index_candidate_edges();
  const RegionGrowing& g = f.g;
  ASSERT_EQ(g.by_edge.size(), 6u);
  const std::array<std::uint32_t, 4> leaving{2, 1, 2, 1};
  for (std::uint32_t v = 0; v < 4; ++v) EXPECT_EQ(g.edges_from[g.rank[v] + 1] - g.edges_from[g.rank[v]], leaving[v]) << v;
  for (std::uint32_t r = 0; r < 4; ++r)
    for (std::uint32_t i = g.edges_from[r]; i < g.edges_from[r + 1]; ++i) {
      const CandidateEdge& e = g.by_edge[i];
      EXPECT_EQ(e.key >> 32, r);
      const V3& v = g.candidates[e.id].v;
      const auto from = std::uint32_t(std::find(g.rank.begin(), g.rank.end(), r) - g.rank.begin());
      const auto to = std::uint32_t(e.key & 0xffffffffu);
      const int k = int(std::find(v.begin(), v.end(), from) - v.begin());
      ASSERT_LT(k, 3);
      EXPECT_EQ(v[(k + 1) % 3], to);
      EXPECT_EQ(v[(k + 2) % 3], e.third);
    }
  EXPECT_EQ(g.accepted, (std::vector<std::uint8_t>{0, 0}));
  EXPECT_EQ(g.in_mesh, (std::vector<std::uint8_t>(4, 0)));
  EXPECT_TRUE(g.sel.triangles.empty());
}

TEST(RegionGrowingPhases, GrowthRejectsAnOverlapAndTheBridgeJoinsTwoRegions) {
  // Region B (3 4 5) is the best seed, region A (0 1 2) the next; candidate 2 overlaps A (it
  // reuses A's directed edge 0 -> 1); candidate 3 shares A's edge 1-2 and only touches B at
  // vertex 3, so growth refuses it and the bridging accepts it.
  const std::vector<Vector3d> pts{{0, 0, 0}, {2, 0, 0}, {1, 1.5, 0}, {2.5, 2, 0}, {4, 2.5, 0}, {3, 3.5, 0}};
  Fixture f(planar(pts));
  f.measure();
  RegionGrowing& g = f.g;
  g.candidates = {candidate({3, 4, 5}), candidate({0, 1, 2}), candidate({0, 1, 3}), candidate({1, 3, 2})};
  g.index_candidate_edges();
  g.grow_regions();
  EXPECT_EQ(g.accepted, (std::vector<std::uint8_t>{1, 1, 0, 0}));
  ASSERT_EQ(g.sel.triangles.size(), 2u);
  EXPECT_EQ(g.in_mesh, (std::vector<std::uint8_t>(6, 1)));
  g.bridge_channels();
  EXPECT_EQ(g.out.selected_triangles, 3u);
  ASSERT_EQ(g.sel.triangles.size(), 3u);
  EXPECT_EQ(g.sel.triangles[2], Triangle(1, 3, 2));
  EXPECT_TRUE(g.candidates.empty());
}

TEST(RegionGrowingPhases, GrowthFromASeedFillsAHexagonFan) {
  // Centre 0 and a unit hexagon 1..6: the six fan triangles, any order, grow from one seed.
  std::vector<Vector3d> pts{Vector3d::Zero()};
  for (int i = 0; i < 6; ++i) pts.emplace_back(std::cos(i * std::numbers::pi / 3), std::sin(i * std::numbers::pi / 3), 0);
  Fixture f(planar(pts));
  f.measure();
  RegionGrowing& g = f.g;
  for (std::uint32_t i : {3u, 1u, 5u, 2u, 6u, 4u}) g.candidates.push_back(candidate({0, i, i % 6 + 1}));
  g.index_candidate_edges();
  g.grow_regions();
  EXPECT_EQ(g.sel.triangles.size(), 6u);
  EXPECT_EQ(g.accepted, (std::vector<std::uint8_t>(6, 1)));
}

TEST(RegionGrowingPhases, FrontClosingFillsTheNarrowCornerOfAnOpenFan) {
  // Five of the six triangles of a hexagon fan: the corner at the centre opens 60 degrees on the
  // hole side, every other boundary corner 240 or 300.
  std::vector<Vector3d> pts{Vector3d::Zero()};
  for (int i = 0; i < 6; ++i) pts.emplace_back(std::cos(i * std::numbers::pi / 3), std::sin(i * std::numbers::pi / 3), 0);
  Fixture f(planar(pts));
  f.measure();
  RegionGrowing& g = f.g;
  for (std::uint32_t i = 1; i <= 5; ++i) add(g.sel, f.cloud, 0, i, i + 1);
  g.close_front_corners();
  EXPECT_EQ(g.out.front_triangles, 1u);
  ASSERT_EQ(g.sel.triangles.size(), 6u);
  EXPECT_TRUE(g.sel.edges.contains(0, 6) && g.sel.edges.contains(6, 1) && g.sel.edges.contains(1, 0));
}

TEST(RegionGrowingPhases, HoleClosingFillsAOneCellHoleAndNotTheBorder) {
  // A 4 x 4 unit grid without its middle cell: a hole of perimeter 4 spacings inside a border of
  // 12. With a limit of 5 only the hole closes, by two triangles.
  TriangulateParams params;
  params.max_hole_perimeter_in_spacings = 5.0;
  Fixture f(planar(grid(4)), params);
  f.measure();
  RegionGrowing& g = f.g;
  for (std::uint32_t y = 0; y < 3; ++y)
    for (std::uint32_t x = 0; x < 3; ++x) {
      if (x == 1 && y == 1) continue;
      const std::uint32_t a = 4 * y + x;
      add(g.sel, f.cloud, a, a + 1, a + 5);
      add(g.sel, f.cloud, a, a + 5, a + 4);
    }
  ASSERT_EQ(g.sel.triangles.size(), 16u);
  g.close_small_holes();
  EXPECT_EQ(g.out.holes_filled, 1u);
  EXPECT_EQ(g.out.fill_triangles, 2u);
  EXPECT_EQ(g.out.pinch_triangles_removed, 0u);
  EXPECT_EQ(g.sel.triangles.size(), 18u);
  EXPECT_TRUE(g.sel.edges.contains(5, 6) && g.sel.edges.contains(6, 10) && g.sel.edges.contains(10, 9) &&
              g.sel.edges.contains(9, 5));
}

TEST(RegionGrowingPhases, AnUnusedPointInsideATriangleSplitsItInThree) {
  Fixture f(planar({{0, 0, 0}, {3, 0, 0}, {0, 3, 0}, {1, 1, 0}}));
  f.measure();
  RegionGrowing& g = f.g;
  add(g.sel, f.cloud, 0, 1, 2);
  g.insert_points();
  EXPECT_EQ(g.out.inserted_points, 1u);
  ASSERT_EQ(g.sel.triangles.size(), 3u);
  for (const Triangle& t : g.sel.triangles) EXPECT_EQ((t.array() == 3).count(), 1);
  const TriangulateResult r = std::move(g).result();
  EXPECT_EQ(r.mesh.triangles.size(), 3u);
  EXPECT_EQ(r.unused_points, 0u);
  EXPECT_EQ(r.stats.input_points, 4u);
  EXPECT_TRUE(std::find(r.stats.counts.begin(), r.stats.counts.end(), std::pair<std::string, std::size_t>{"inserted_points", 1}) !=
              r.stats.counts.end());
}

}  // namespace
}  // namespace pointsurf::detail
