// SPDX-License-Identifier: GPL-3.0-or-later
// The phases of the MST orientation (normals/detail/mst_orientation.h), each run alone on a
// small cloud whose answer is known by construction.
#include "normals/detail/mst_orientation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace pointsurf {
namespace {

using detail::MstOrientation;
using Edge = MstOrientation::Edge;

const Vector3d kUp = Vector3d::UnitZ();
const Vector3d kX = Vector3d::UnitX();

PointCloud cloud_of(std::vector<Vector3d> positions, std::vector<Vector3d> normals) {
  PointCloud cloud;
  cloud.positions = std::move(positions);
  cloud.normals = std::move(normals);
  return cloud;
}

// Points on the x axis, all with the normal `normal`.
PointCloud line(const std::vector<double>& xs, const Vector3d& normal = kUp) {
  std::vector<Vector3d> positions;
  for (double x : xs) positions.emplace_back(x, 0.0, 0.0);
  return cloud_of(positions, std::vector<Vector3d>(xs.size(), normal));
}

OrientParams with_k(int k) {
  OrientParams params;
  params.k = k;
  return params;
}

std::set<Edge> undirected(const std::vector<Edge>& edges) {
  std::set<Edge> out;
  for (const auto& [a, b] : edges) out.insert(std::minmax(a, b));
  return out;
}

std::set<Edge> forest_of_ends(const MstOrientation& mst) {
  std::vector<Edge> edges;
  for (const std::uint64_t key : mst.keys) edges.push_back(mst.ends(key & MstOrientation::kSlotMask));
  return undirected(edges);
}

TEST(MstOrientationPhases, KnnGraphHoldsEachPointsNearestOthersAndReach) {
  // Gaps 1, 2, 4: each point's nearest other point is unique.
  const PointCloud cloud = line({0.0, 1.0, 3.0, 7.0});
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  ASSERT_EQ(mst.degree, 1u);
  ASSERT_EQ(mst.slots, 4u);
  mst.build_knn_graph({});
  EXPECT_EQ(mst.target, (std::vector<std::uint32_t>{1, 0, 1, 2}));
  EXPECT_EQ(mst.reach, (std::vector<float>{1.0f, 1.0f, 4.0f, 16.0f}));  // squared distance to the nearest
  // Parallel normals, every edge one reach long: all weights equal, and in [0, 1].
  for (const float w : mst.weight) {
    EXPECT_EQ(w, mst.weight[0]);
    EXPECT_GT(w, 0.0f);
    EXPECT_LT(w, 1.0f);
  }
}

TEST(MstOrientationPhases, KnnGraphEdgeAcrossACreaseWeighsMore) {
  PointCloud cloud = line({0.0, 1.0, 3.0, 7.0});
  cloud.normals[3] = kX;  // perpendicular to its neighbour's
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  mst.build_knn_graph({});
  EXPECT_GT(mst.weight[3], mst.weight[2]);
  EXPECT_EQ(mst.weight[0], mst.weight[2]);
}

TEST(MstOrientationPhases, JoinsASamplingGapButNotSeparateObjects) {
  // Two runs of three points 1 apart, 3 apart: within 3 reaches (reach 2), so one join.
  {
    const PointCloud cloud = line({0.0, 1.0, 2.0, 5.0, 6.0, 7.0});
    const OrientParams params = with_k(2);
    MstOrientation mst(cloud, params, nullptr);
    mst.build_knn_graph({});
    mst.join_components();
    EXPECT_EQ(undirected(mst.joins), (std::set<Edge>{{2, 3}}));  // x = 2 to x = 5
  }
  // The second run 100 away is a separate object: no join.
  {
    const PointCloud cloud = line({0.0, 1.0, 2.0, 102.0, 103.0, 104.0});
    const OrientParams params = with_k(2);
    MstOrientation mst(cloud, params, nullptr);
    mst.build_knn_graph({});
    mst.join_components();
    EXPECT_TRUE(mst.joins.empty());
  }
}

TEST(MstOrientationPhases, SortedEdgesAreDistinctAndLightestFirst) {
  PointCloud cloud = line({0.0, 1.0, 3.0, 7.0});
  const OrientParams params = with_k(1);
  {
    // Edges 0-1 (found from both ends, kept once), 2-1 and 3-2, all of equal weight: by slot.
    MstOrientation mst(cloud, params, nullptr);
    mst.build_knn_graph({});
    mst.join_components();
    mst.sort_edges();
    ASSERT_EQ(mst.keys.size(), 3u);
    EXPECT_TRUE(std::is_sorted(mst.keys.begin(), mst.keys.end()));
    EXPECT_EQ(mst.ends(mst.keys[0] & MstOrientation::kSlotMask), Edge(0, 1));
    EXPECT_EQ(mst.ends(mst.keys[1] & MstOrientation::kSlotMask), Edge(2, 1));
    EXPECT_EQ(mst.ends(mst.keys[2] & MstOrientation::kSlotMask), Edge(3, 2));
    EXPECT_TRUE(mst.weight.empty());
  }
  {
    // A perpendicular normal at point 0 puts its edge last.
    cloud.normals[0] = kX;
    MstOrientation mst(cloud, params, nullptr);
    mst.build_knn_graph({});
    mst.join_components();
    mst.sort_edges();
    ASSERT_EQ(mst.keys.size(), 3u);
    EXPECT_EQ(mst.ends(mst.keys.back() & MstOrientation::kSlotMask), Edge(0, 1));
  }
}

TEST(MstOrientationPhases, JoinsAreSortedAsEdgesAfterTheKnnSlots) {
  const PointCloud cloud = line({0.0, 1.0, 2.0, 5.0, 6.0, 7.0});
  const OrientParams params = with_k(2);
  MstOrientation mst(cloud, params, nullptr);
  mst.build_knn_graph({});
  mst.join_components();
  mst.sort_edges();
  // Each run of three is a triangle (3 distinct edges), plus the join.
  EXPECT_EQ(forest_of_ends(mst), (std::set<Edge>{{0, 1}, {0, 2}, {1, 2}, {3, 4}, {3, 5}, {4, 5}, {2, 3}}));
  EXPECT_EQ(mst.keys.size(), 7u);
}

TEST(MstOrientationPhases, SpanningForestOfACycleDropsItsHeaviestEdge) {
  // A 1 x 2 rectangle, k = 2: the kNN graph is the 4-cycle 0-1-3-2-0 (short sides 0-1, 2-3).
  // A tilted normal at 3 makes 1-3 the heaviest edge of the cycle.
  PointCloud cloud = cloud_of({{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {1, 2, 0}}, {kUp, kUp, kUp, kUp});
  cloud.normals[3] = Vector3d(0.3, 0.0, 1.0).normalized();
  const OrientParams params = with_k(2);
  MstOrientation mst(cloud, params, nullptr);
  mst.build_knn_graph({});
  mst.join_components();
  mst.sort_edges();
  ASSERT_EQ(forest_of_ends(mst), (std::set<Edge>{{0, 1}, {2, 3}, {0, 2}, {1, 3}}));
  mst.span_forest();
  EXPECT_EQ(undirected(mst.forest), (std::set<Edge>{{0, 1}, {2, 3}, {0, 2}}));
  for (std::uint32_t i = 1; i < 4; ++i) EXPECT_EQ(mst.sets.find(i), mst.sets.find(0));
  EXPECT_TRUE(mst.keys.empty());
  EXPECT_TRUE(mst.target.empty());
}

TEST(MstOrientationPhases, SpanningForestKeepsSeparateObjectsApart) {
  const PointCloud cloud = line({0.0, 1.0, 2.0, 102.0, 103.0, 104.0});
  const OrientParams params = with_k(2);
  MstOrientation mst(cloud, params, nullptr);
  mst.build_knn_graph({});
  mst.join_components();
  mst.sort_edges();
  mst.span_forest();
  EXPECT_EQ(mst.forest.size(), 4u);  // two trees of three points
  EXPECT_EQ(mst.sets.find(0), mst.sets.find(2));
  EXPECT_EQ(mst.sets.find(3), mst.sets.find(5));
  EXPECT_NE(mst.sets.find(0), mst.sets.find(3));
}

TEST(MstOrientationPhases, AdjacencyOfAStarInCompressedRows) {
  const PointCloud cloud = line({0.0, 1.0, 2.0, 3.0});
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  mst.forest = {{0, 1}, {1, 2}, {1, 3}};  // a star around 1
  mst.build_adjacency();
  EXPECT_EQ(mst.offsets, (std::vector<std::size_t>{0, 1, 4, 5, 6}));
  EXPECT_EQ(mst.adjacency, (std::vector<std::uint32_t>{1, 0, 2, 3, 1, 1}));
  EXPECT_TRUE(mst.forest.empty());
}

TEST(MstOrientationPhases, ComponentsAreLabelledInPointOrderWithCentroids) {
  // Two objects far apart: points 0, 2, 4 near the origin, 1, 3 near x = 100.
  const PointCloud cloud = cloud_of({{0, 0, 0}, {100, 0, 0}, {1, 0, 0}, {101, 0, 0}, {3, 0, 0}},
                                    std::vector<Vector3d>(5, kUp));
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  mst.build_knn_graph({});
  mst.join_components();
  mst.sort_edges();
  mst.span_forest();
  mst.label_components();
  ASSERT_EQ(mst.components(), 2u);
  EXPECT_EQ(mst.component, (std::vector<std::uint32_t>{0, 1, 0, 1, 0}));
  EXPECT_EQ(mst.count, (std::vector<std::size_t>{3, 2}));
  EXPECT_EQ(mst.origin, Vector3d(0, 0, 0));
  EXPECT_EQ(mst.centroid[0], Vector3d(4.0 / 3.0, 0, 0));
  EXPECT_EQ(mst.centroid[1], Vector3d(100.5, 0, 0));
}

TEST(MstOrientationPhases, SeedIsTheFarthestPointWithADirection) {
  // One component centred on x = 2: the farthest points 0 and 4 (x = 0 and 4) have no normal,
  // so the seed is the next farthest with one, point 1 (x = 1; 3 ties with it and comes later).
  PointCloud cloud = line({0.0, 1.0, 2.0, 3.0, 4.0});
  cloud.normals[0] = cloud.normals[4] = Vector3d::Zero();
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  mst.component.assign(5, 0);
  mst.centroid = {Vector3d(2, 0, 0)};
  mst.choose_seeds();
  EXPECT_EQ(mst.seed, (std::vector<std::uint32_t>{1}));
  // A component whose points all lack a normal has no seed.
  mst.component = {1, 0, 0, 0, 1};
  mst.centroid = {Vector3d(2, 0, 0), Vector3d(2, 0, 0)};
  mst.choose_seeds();
  EXPECT_EQ(mst.seed, (std::vector<std::uint32_t>{1, std::numeric_limits<std::uint32_t>::max()}));
}

TEST(MstOrientationPhases, PropagationMakesAPathAgreeWithItsSeed) {
  // The path 0-1-2-3 on the x axis, centroid x = 1.5, seed 0 whose normal -x faces away from
  // the centroid. Point 2 has no normal: 3 is compared with 1 as oriented.
  const PointCloud cloud = cloud_of({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}}, {-kX, kX, Vector3d::Zero(), -kX});
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  mst.forest = {{0, 1}, {1, 2}, {2, 3}};
  mst.build_adjacency();
  mst.component.assign(4, 0);
  mst.centroid = {Vector3d(1.5, 0, 0)};
  mst.seed = {0};
  mst.propagate_from_seeds();
  EXPECT_EQ(mst.flip, (std::vector<std::uint8_t>{0, 1, 0, 0}));
  // The seed itself is flipped when it faces the centroid.
  mst.flip.assign(4, 0);
  mst.seed = {3};
  mst.propagate_from_seeds();
  EXPECT_EQ(mst.flip, (std::vector<std::uint8_t>{1, 0, 0, 1}));
}

// Points of a unit sphere (Fibonacci lattice), with normals `sign` times outward.
PointCloud sphere(double sign, std::size_t count = 200) {
  std::vector<Vector3d> positions, normals;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (std::size_t i = 0; i < count; ++i) {
    const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(count);
    const double r = std::sqrt(1.0 - z * z);
    positions.emplace_back(r * std::cos(golden * double(i)), r * std::sin(golden * double(i)), z);
    normals.push_back(sign * positions.back());
  }
  return cloud_of(positions, normals);
}

// A flat 10 x 10 grid at z = 0 with normal `normal`.
PointCloud grid(const Vector3d& normal) {
  std::vector<Vector3d> positions;
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 10; ++x) positions.emplace_back(x, y, 0.0);
  return cloud_of(positions, std::vector<Vector3d>(positions.size(), normal));
}

// Runs the phases before tally_votes on one component labelled by hand.
void one_component(MstOrientation& mst) {
  mst.origin = mst.cloud.positions[0];
  mst.component.assign(mst.n, 0);
  Vector3d sum = Vector3d::Zero();
  for (const Vector3d& p : mst.cloud.positions) sum += p - mst.origin;
  mst.centroid = {sum / double(mst.n)};
}

TEST(MstOrientationPhases, InwardSphereVotesAllAgainstAndIsFlipped) {
  const PointCloud cloud = sphere(-1.0);
  const OrientParams params;
  MstOrientation mst(cloud, params, nullptr);
  one_component(mst);
  mst.tally_votes();
  ASSERT_EQ(mst.votes.directed, (std::vector<std::size_t>{200}));
  EXPECT_LT(mst.votes.signed_sum[0], 0.0);
  EXPECT_NEAR(-mst.votes.signed_sum[0], mst.votes.absolute_sum[0], 1e-9);  // every vote against
  EXPECT_LT(mst.votes.normal_sum[0].norm(), 0.1 * 200);                    // closed: no net normal
  mst.decide_component_signs();
  EXPECT_EQ(mst.terrain, (std::vector<std::uint8_t>{0}));
  EXPECT_EQ(mst.flip_component, (std::vector<std::uint8_t>{1}));
}

TEST(MstOrientationPhases, OutwardSphereIsKept) {
  const PointCloud cloud = sphere(1.0);
  const OrientParams params;
  MstOrientation mst(cloud, params, nullptr);
  one_component(mst);
  mst.tally_votes();
  EXPECT_NEAR(mst.votes.signed_sum[0], mst.votes.absolute_sum[0], 1e-9);
  mst.decide_component_signs();
  EXPECT_EQ(mst.terrain, (std::vector<std::uint8_t>{0}));
  EXPECT_EQ(mst.flip_component, (std::vector<std::uint8_t>{0}));
}

TEST(MstOrientationPhases, DownwardPlaneIsTerrainAndTurnedUp) {
  const PointCloud cloud = grid(-kUp);
  const OrientParams params;
  MstOrientation mst(cloud, params, nullptr);
  one_component(mst);
  mst.tally_votes();
  EXPECT_DOUBLE_EQ(mst.votes.horizontal_sum[0], 100.0);
  EXPECT_EQ(mst.votes.normal_sum[0], Vector3d(0, 0, -100));
  mst.decide_component_signs();
  EXPECT_EQ(mst.terrain, (std::vector<std::uint8_t>{1}));
  EXPECT_EQ(mst.flip_component, (std::vector<std::uint8_t>{1}));
  EXPECT_TRUE(mst.has_terrain());
}

// Points of LAS class 2 decide: on an outward sphere whose bottom cap is labelled ground, the
// ground must face up, so the whole component is reversed, and it counts as terrain.
TEST(MstOrientationPhases, ClassifiedGroundDecidesTheSign) {
  PointCloud cloud = sphere(1.0);
  std::vector<double>& classes = cloud.fields.add("classification", cloud.size(), ScalarType::UInt8).values;
  for (std::size_t i = 0; i < cloud.size(); ++i) classes[i] = cloud.positions[i].z() < -0.5 ? 2.0 : 1.0;
  const OrientParams params;
  MstOrientation mst(cloud, params, nullptr);
  one_component(mst);
  mst.tally_votes();
  EXPECT_LT(mst.votes.ground_sum[0], 0.0);
  EXPECT_NEAR(-mst.votes.ground_sum[0], mst.votes.ground_absolute[0], 1e-9);
  mst.decide_component_signs();
  EXPECT_EQ(mst.terrain, (std::vector<std::uint8_t>{1}));
  EXPECT_EQ(mst.flip_component, (std::vector<std::uint8_t>{1}));
  EXPECT_DOUBLE_EQ(mst.agreement[0], 1.0);
}

// A closed sphere has a top and a bottom over its columns: not open, so not terrain, though
// its extent in z is small against nothing; a plane has one layer everywhere.
TEST(MstOrientationPhases, ColumnsTellOpenSheetsFromClosedSurfaces) {
  const PointCloud ball = sphere(1.0, 2000);
  const OrientParams params;
  MstOrientation closed(ball, params, nullptr);
  one_component(closed);
  closed.tally_votes();
  ASSERT_GT(closed.votes.cells[0], 0u);
  EXPECT_LT(double(closed.votes.single_layer[0]), 0.15 * double(closed.votes.cells[0]));
  const PointCloud plane = grid(kUp);
  MstOrientation open(plane, params, nullptr);
  one_component(open);
  open.tally_votes();
  ASSERT_GT(open.votes.cells[0], 0u);
  EXPECT_EQ(open.votes.single_layer[0], open.votes.cells[0]);
  EXPECT_DOUBLE_EQ(open.votes.bottom_sum[0], double(open.votes.columns[0]));
}

TEST(MstOrientationPhases, ComponentSignsToggleOnlyPointsWithADirection) {
  PointCloud cloud = line({0.0, 1.0, 2.0, 10.0});
  cloud.normals[1] = Vector3d::Zero();
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  mst.component = {0, 0, 0, 1};
  mst.flip = {1, 0, 0, 0};
  mst.flip_component = {1, 0};
  mst.apply_component_signs();
  EXPECT_EQ(mst.flip, (std::vector<std::uint8_t>{0, 0, 1, 0}));
}

TEST(MstOrientationPhases, TerrainRegionsAreCutAtCreasesAndTurnedUp) {
  // A path of ground (up, up), a wall (+x) and an upside-down roof (-z, -z): creases at both
  // ends of the wall cut it into the regions {0, 1}, {2}, {3, 4}; only the roof faces down.
  const PointCloud cloud = cloud_of({{0, 0, 0}, {1, 0, 0}, {2, 0, 1}, {3, 0, 2}, {4, 0, 2}}, {kUp, kUp, kX, -kUp, -kUp});
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  mst.forest = {{0, 1}, {1, 2}, {2, 3}, {3, 4}};
  mst.build_adjacency();
  mst.component.assign(5, 0);
  mst.terrain = {1};
  mst.cut_at_creases();
  EXPECT_EQ(mst.regions.find(0), mst.regions.find(1));
  EXPECT_EQ(mst.regions.find(3), mst.regions.find(4));
  EXPECT_NE(mst.regions.find(1), mst.regions.find(2));
  EXPECT_NE(mst.regions.find(2), mst.regions.find(3));
  mst.flip.assign(5, 0);
  mst.turn_up_level_regions();
  EXPECT_EQ(mst.flip, (std::vector<std::uint8_t>{0, 0, 0, 1, 1}));
}

TEST(MstOrientationPhases, CreasesOutsideTerrainAreNotCut) {
  const PointCloud cloud = cloud_of({{0, 0, 0}, {1, 0, 0}}, {kUp, -kUp});
  const OrientParams params = with_k(1);
  MstOrientation mst(cloud, params, nullptr);
  mst.forest = {{0, 1}};
  mst.build_adjacency();
  mst.component.assign(2, 0);
  mst.terrain = {0};
  EXPECT_FALSE(mst.has_terrain());
  mst.cut_at_creases();
  EXPECT_NE(mst.regions.find(0), mst.regions.find(1));  // nothing united
  mst.turn_up_level_regions();
  EXPECT_EQ(mst.flip, (std::vector<std::uint8_t>{0, 0}));
}

TEST(MstOrientationPhases, DegreeIsCappedAtTheOtherPoints) {
  const PointCloud cloud = line({0.0, 1.0});
  const OrientParams params = with_k(5);
  MstOrientation mst(cloud, params, nullptr);
  EXPECT_EQ(mst.degree, 1u);  // k is capped at n - 1
  EXPECT_EQ(mst.slots, 2u);
  EXPECT_EQ(mst.flip, (std::vector<std::uint8_t>{0, 0}));
}

}  // namespace
}  // namespace pointsurf
