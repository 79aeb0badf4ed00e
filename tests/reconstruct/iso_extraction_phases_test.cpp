// SPDX-License-Identifier: GPL-3.0-or-later
// The phases of extract_iso_surface (reconstruct/detail/iso_extraction.h), each run alone on a
// plane through a small lattice, where the answer is known by construction.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "reconstruct/detail/iso_extraction.h"

namespace pointsurf {
namespace {

using detail::IsoFunction;
using detail::IsoLattice;
using detail::IsoSurface;
using detail::IsoSurfaceParams;
using detail::iso::Extraction;
using Cell = std::array<std::uint32_t, 3>;
using Refined = std::function<bool(int level, const Cell& cell)>;

/// The plane x = x0 of the unit cube: value x - x0 (inside where smaller), exact gradient, on
/// the octree that `refined` describes.
class Plane : public IsoFunction {
 public:
  Plane(double x0, int depth, Refined refined) : x0_(x0), refined_(std::move(refined)) {
    lattice_.size = 1.0;
    lattice_.depth = depth;
  }
  void corner_values(int level, const std::uint32_t* corners, std::size_t n, double* values) const override {
    for (std::size_t i = 0; i < n; ++i) values[i] = value(lattice_.corner_position(level, {corners[3 * i], corners[3 * i + 1], corners[3 * i + 2]}));
  }
  double value(const Eigen::Vector3d& p) const override { return p.x() - x0_; }
  Eigen::Vector3d gradient(const Eigen::Vector3d&) const override { return Eigen::Vector3d::UnitX(); }
  bool refined(int level, const Cell& cell) const override { return refined_(level, cell); }
  const IsoLattice& lattice() const { return lattice_; }

 private:
  double x0_;
  Refined refined_;
  IsoLattice lattice_;
};

IsoSurfaceParams outside_larger() {
  IsoSurfaceParams p;
  p.inside_positive = false;
  return p;
}

std::set<Cell> cells_of(const std::vector<detail::iso::Key>& keys) {
  std::set<Cell> cells;
  for (detail::iso::Key k : keys) cells.insert(detail::iso::unpack(k));
  return cells;
}

std::set<Cell> active_cells(const Extraction& x) {
  using namespace detail::iso;
  std::set<Cell> cells;
  for (const auto& b : x.bricks()) {
    const auto o = unpack(b->key);
    for (int c = 0; c < kB * kB * kB; ++c)
      if (b->state[std::size_t(c)] & kActive)
        cells.insert({o[0] * kB + std::uint32_t(c % kB), o[1] * kB + std::uint32_t(c / kB % kB), o[2] * kB + std::uint32_t(c / (kB * kB))});
  }
  return cells;
}

bool is_origin(const Cell& c) { return c[0] == 0 && c[1] == 0 && c[2] == 0; }

TEST(IsoExtractionPhases, ConstructorRejectsBadLattices) {
  const Plane f(0.3, 2, [](int, const Cell&) { return true; });
  IsoLattice deep = f.lattice();
  deep.depth = detail::iso::kMaxDepth + 1;
  IsoLattice flat = f.lattice();
  flat.size = 0.0;
  const IsoSurfaceParams params;
  EXPECT_THROW(Extraction(f, deep, params), UsageError);
  EXPECT_THROW(Extraction(f, flat, params), UsageError);
}

TEST(IsoExtractionPhases, FindLeavesOfAFullOctree) {
  const Plane f(0.3, 2, [](int, const Cell&) { return true; });
  const IsoSurfaceParams params;
  Extraction x(f, f.lattice(), params);
  x.find_leaves();
  EXPECT_EQ(x.depth(), 2);
  EXPECT_EQ(x.seeds().size(), 64u);
  EXPECT_EQ(cells_of(x.seeds()).size(), 64u);
  EXPECT_TRUE(x.coarse_leaves().empty());
}

TEST(IsoExtractionPhases, FindLeavesOfOneRefinedBranch) {
  // only the cell at the origin is refined, at every level: 7 leaves per coarse level
  const Plane f(0.3, 3, [](int, const Cell& c) { return is_origin(c); });
  const IsoSurfaceParams params;
  Extraction x(f, f.lattice(), params);
  x.find_leaves();
  EXPECT_EQ(x.depth(), 3);
  std::set<Cell> expected;
  for (std::uint32_t k = 0; k < 8; ++k) expected.insert({k & 1, k >> 1 & 1, k >> 2});
  EXPECT_EQ(cells_of(x.seeds()), expected);
  ASSERT_EQ(x.coarse_leaves().size(), 14u);
  int level1 = 0, level2 = 0;
  for (const auto& [level, key] : x.coarse_leaves()) {
    EXPECT_FALSE(is_origin(detail::iso::unpack(key)));
    level1 += level == 1, level2 += level == 2;
  }
  EXPECT_EQ(level1, 7);
  EXPECT_EQ(level2, 7);
}

TEST(IsoExtractionPhases, FindLeavesLowersTheDepthToTheDeepestLeaves) {
  const Plane f(0.3, 4, [](int level, const Cell&) { return level < 2; });
  const IsoSurfaceParams params;
  Extraction x(f, f.lattice(), params);
  x.find_leaves();
  EXPECT_EQ(x.depth(), 2);
  EXPECT_EQ(cells_of(x.seeds()).size(), 64u);
  EXPECT_TRUE(x.coarse_leaves().empty());
}

TEST(IsoExtractionPhases, SeedCoarseCrossingsFindsTheFinestCellsOfThePlane) {
  // depth 2 (cells of 1/4): the level-1 cell (1, 1, 1) refined, the other 7 coarse leaves. The
  // plane x = 0.3 crosses the coarse leaves with x = 0 along their x edges, in the finest cells
  // with x = 1: all 16 of them are seeded, besides the 8 finest leaves in [2, 4)^3.
  const Plane f(0.3, 2, [](int level, const Cell& c) { return level == 0 || (c[0] == 1 && c[1] == 1 && c[2] == 1); });
  const IsoSurfaceParams params = outside_larger();
  Extraction x(f, f.lattice(), params);
  x.find_leaves();
  ASSERT_EQ(x.coarse_leaves().size(), 7u);
  x.seed_coarse_crossings();
  std::set<Cell> expected;
  for (std::uint32_t y = 0; y < 4; ++y)
    for (std::uint32_t z = 0; z < 4; ++z) expected.insert({1, y, z});
  for (std::uint32_t k = 0; k < 8; ++k) expected.insert({2 + (k & 1), 2 + (k >> 1 & 1), 2 + (k >> 2)});
  EXPECT_EQ(x.seeds().size(), 24u);  // sorted and unique
  EXPECT_TRUE(std::is_sorted(x.seeds().begin(), x.seeds().end()));
  EXPECT_EQ(cells_of(x.seeds()), expected);
  EXPECT_TRUE(x.coarse_leaves().empty());
}

TEST(IsoExtractionPhases, FollowingTheSurfaceReachesEveryCrossedCell) {
  // depth 4 (16 cells a side, 2^3 bricks), refined only towards the origin: the coarse leaves
  // seed some of the cells the plane x = 0.3 crosses (x = 4), the following finds all 256.
  const Plane f(0.3, 4, [](int, const Cell& c) { return is_origin(c); });
  const IsoSurfaceParams params = outside_larger();
  Extraction x(f, f.lattice(), params);
  x.find_leaves();
  x.seed_coarse_crossings();
  std::size_t seeded_on_plane = 0;
  for (const Cell& c : cells_of(x.seeds())) seeded_on_plane += c[0] == 4;
  EXPECT_GT(seeded_on_plane, 0u);
  EXPECT_LT(seeded_on_plane, 256u);
  x.queue_seeds();
  EXPECT_TRUE(x.seeds().empty());
  int rounds = 0;
  while (x.follow_round()) ++rounds;
  EXPECT_GE(rounds, 1);
  std::set<Cell> expected;
  for (std::uint32_t y = 0; y < 16; ++y)
    for (std::uint32_t z = 0; z < 16; ++z) expected.insert({4, y, z});
  EXPECT_EQ(active_cells(x), expected);
  x.index_bricks();
  for (std::size_t i = 1; i < x.bricks().size(); ++i) EXPECT_LT(x.bricks()[i - 1]->key, x.bricks()[i]->key);
}

/// A full octree of depth 2 cut by x = 0.3, run up to (not including) the vertices.
Extraction plane_up_to_edges(const Plane& f, const IsoSurfaceParams& params) {
  Extraction x(f, f.lattice(), params);
  x.find_leaves();
  x.seed_coarse_crossings();
  x.queue_seeds();
  while (x.follow_round()) {
  }
  x.index_bricks();
  x.collect_crossed_edges();
  return x;
}

TEST(IsoExtractionPhases, CollectCrossedEdgesOwnsEachCrossedEdgeOnce) {
  // the crossed edges: the x edges from x = 1/4 to 1/2, one per corner (y, z) in 0..4
  const Plane f(0.3, 2, [](int, const Cell&) { return true; });
  const IsoSurfaceParams params = outside_larger();
  Extraction x = plane_up_to_edges(f, params);
  ASSERT_EQ(x.bricks().size(), 1u);
  const auto& edges = x.bricks()[0]->edges;
  ASSERT_EQ(edges.size(), 25u);
  for (std::uint16_t e : edges) {
    EXPECT_EQ(e % 3, 0) << "an x edge";
    EXPECT_EQ(e / 3 % detail::iso::kC, 1) << "from x = 1";
  }
  EXPECT_EQ(x.bricks()[0]->first_vertex, 0u);
}

TEST(IsoExtractionPhases, PlaceVerticesPutsThemOnThePlane) {
  const Plane f(0.3, 2, [](int, const Cell&) { return true; });
  const IsoSurfaceParams params = outside_larger();
  Extraction x = plane_up_to_edges(f, params);
  x.place_vertices();
  const IsoSurface& s = x.surface();
  ASSERT_EQ(s.vertices.size(), 25u);
  std::set<std::pair<long, long>> yz;
  for (std::size_t i = 0; i < s.vertices.size(); ++i) {
    EXPECT_NEAR(s.vertices[i].x(), 0.3, 1e-12);
    yz.insert({std::lround(4 * s.vertices[i].y()), std::lround(4 * s.vertices[i].z())});
    EXPECT_NEAR((s.normals[i] - Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-12);  // outward: +x
  }
  EXPECT_EQ(yz.size(), 25u);
}

TEST(IsoExtractionPhases, TriangulateCellsSplitsEachCrossedCellInTwo) {
  // 16 crossed cells, each a quadrilateral: 32 triangles, facing +x (outside), covering the
  // unit square x = 0.3
  const Plane f(0.3, 2, [](int, const Cell&) { return true; });
  const IsoSurfaceParams params = outside_larger();
  Extraction x = plane_up_to_edges(f, params);
  x.place_vertices();
  x.triangulate_cells();
  ASSERT_EQ(x.chunks().size(), 1u);
  EXPECT_TRUE(x.chunks()[0].centres.empty());
  const auto& triangles = x.chunks()[0].triangles;
  ASSERT_EQ(triangles.size(), 32u);
  double area = 0.0;
  for (const auto& t : triangles) {
    const auto& v = x.surface().vertices;
    const Eigen::Vector3d n = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);
    EXPECT_GT(n.x(), 0.0);
    area += 0.5 * n.norm();
  }
  EXPECT_NEAR(area, 1.0, 1e-12);
  const IsoSurface s = std::move(x).result();
  EXPECT_EQ(s.vertices.size(), 25u);
  EXPECT_EQ(s.triangles.size(), 32u);
}

TEST(IsoExtractionPhases, CellLoopsAroundOneAndTwoCorners) {
  using detail::iso::cell_loops;
  std::array<int, 12> edges;
  std::array<int, 5> start;
  std::array<double, 8> w;
  w.fill(-1.0);
  w[0] = 1.0;  // corner 0 inside: one triangle on its three edges (0, 4, 8: x, y, z from corner 0)
  ASSERT_EQ(cell_loops(w, edges, start), 1);
  EXPECT_EQ(start[1] - start[0], 3);
  std::set<int> loop(edges.begin(), edges.begin() + 3);
  EXPECT_EQ(loop, (std::set<int>{0, 4, 8}));
  w[7] = 1.0;  // and the opposite corner: a second triangle on the edges of corner 7
  ASSERT_EQ(cell_loops(w, edges, start), 2);
  EXPECT_EQ(start[1] - start[0], 3);
  EXPECT_EQ(start[2] - start[1], 3);
  std::set<int> all(edges.begin(), edges.begin() + 6);
  EXPECT_EQ(all, (std::set<int>{0, 4, 8, 3, 7, 11}));
  w.fill(1.0);  // all inside: nothing
  EXPECT_EQ(cell_loops(w, edges, start), 0);
}

TEST(IsoExtractionPhases, QuadraticRootIsExactOnAQuadratic) {
  using detail::iso::quadratic_root;
  auto q = [](double t) { return (t - 0.3) * (t + 2.0); };
  EXPECT_NEAR(quadratic_root(q(0.0), q(0.5), q(1.0)), 0.3, 1e-14);
  EXPECT_DOUBLE_EQ(quadratic_root(1.0, 0.0, -1.0), 0.5);  // a line: the linear root
}

TEST(IsoExtractionPhases, AppendChunksNumbersCentresAfterTheEdgeVertices) {
  using detail::iso::ChunkOutput;
  using detail::iso::kCentre;
  IsoSurface s;
  s.vertices = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)};
  s.normals = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ()};
  std::vector<ChunkOutput> chunks(2);
  chunks[0].centres = {Eigen::Vector3d(0, 1, 0)};
  chunks[0].centre_normals = {Eigen::Vector3d::UnitZ()};
  chunks[0].triangles = {{0, 1, kCentre | 0}};
  chunks[1].centres = {Eigen::Vector3d(0, 2, 0), Eigen::Vector3d(0, 3, 0)};
  chunks[1].centre_normals = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ()};
  chunks[1].triangles = {{1, 0, kCentre | 1}};
  detail::iso::append_chunks(chunks, s);
  ASSERT_EQ(s.vertices.size(), 5u);
  ASSERT_EQ(s.normals.size(), 5u);
  EXPECT_EQ(s.vertices[2], Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(s.vertices[4], Eigen::Vector3d(0, 3, 0));
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.triangles[0], (std::array<std::uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(s.triangles[1], (std::array<std::uint32_t, 3>{1, 0, 4}));
}

}  // namespace
}  // namespace pointsurf
