// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/spatial/voxel_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using Points = std::vector<Eigen::Vector3d>;

// A unit sphere surface (a scan-like 2D density), a dense blob on it and sparse far points:
// kNN radii differing by 100x, so wide rings and the kd-tree fallback are both exercised.
Points uneven_points(std::uint64_t seed = 5) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  Points p;
  for (int i = 0; i < 4000; ++i) p.push_back(Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized());
  for (int i = 0; i < 1500; ++i) p.push_back(Eigen::Vector3d(1, 0, 0) + 0.01 * Eigen::Vector3d(g(rng), g(rng), g(rng)));
  for (int i = 0; i < 40; ++i) p.push_back(20.0 * Eigen::Vector3d(g(rng), g(rng), g(rng)));
  return p;
}


// Every point's list from the grid, indexed by point; each point must be visited once.
template <class Run>
std::vector<std::vector<Neighbor>> collect(std::size_t n, Run run) {
  std::vector<std::vector<Neighbor>> lists(n);
  std::vector<int> visits(n, 0);
  std::mutex mutex;
  run([&](std::uint32_t i, std::span<const Neighbor> nb) {
    std::lock_guard lock(mutex);
    ++visits[i];
    lists[i].assign(nb.begin(), nb.end());
  });
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(visits[i], 1) << "point " << i;
  return lists;
}

// The same indices and the same squared distances, bit for bit.
void expect_same(const std::vector<Neighbor>& expected, const std::vector<Neighbor>& actual, std::size_t point) {
  ASSERT_EQ(expected.size(), actual.size()) << "point " << point;
  for (std::size_t j = 0; j < expected.size(); ++j) {
    ASSERT_EQ(expected[j].index, actual[j].index) << "point " << point << " rank " << j;
    ASSERT_EQ(expected[j].squared_distance, actual[j].squared_distance) << "point " << point << " rank " << j;
  }
}

void expect_knn_like_tree(const Points& points, double cell, std::size_t k) {
  const KdTree tree(points);
  const VoxelGrid grid(points, cell);
  const auto lists = collect(points.size(), [&](const VoxelGrid::Visit& v) { grid.for_each_knn(k, v); });
  std::vector<Neighbor> expected;
  for (std::size_t i = 0; i < points.size(); ++i) {
    tree.knn(points[i], k, expected);
    expect_same(expected, lists[i], i);
  }
}

void expect_radius_like_tree(const Points& points, double cell, double radius) {
  const KdTree tree(points);
  const VoxelGrid grid(points, cell);
  const auto lists = collect(points.size(), [&](const VoxelGrid::Visit& v) { grid.for_each_radius(radius, v); });
  const std::vector<std::uint32_t> counts = grid.count_within(radius, 7);
  std::vector<Neighbor> expected;
  for (std::size_t i = 0; i < points.size(); ++i) {
    tree.radius(points[i], radius, expected);
    expect_same(expected, lists[i], i);
    ASSERT_EQ(counts[i], std::min<std::size_t>(expected.size(), 7)) << "point " << i;
  }
}

TEST(VoxelGrid, KnnEqualsTheKdTreeForAnyCellSize) {
  const Points p = test::random_box_points(3000, 200);
  const double tuned = VoxelGrid::knn_cell_size(p, 12);
  EXPECT_GT(tuned, 0.0);
  for (const double cell : {0.01, 0.05, tuned, 0.3, 5.0}) {
    SCOPED_TRACE(cell);
    expect_knn_like_tree(p, cell, 12);
  }
}

TEST(VoxelGrid, KnnBreaksTiesByIndexOnALattice) {
  const Points p = test::lattice_points(9);
  for (const double cell : {0.7, 1.0, 2.0}) {
    SCOPED_TRACE(cell);
    expect_knn_like_tree(p, cell, 7);
    expect_knn_like_tree(p, cell, 27);
  }
}

TEST(VoxelGrid, KnnOnUnevenDensityUsesWiderRingsAndTheTree) {
  const Points p = uneven_points();
  expect_knn_like_tree(p, VoxelGrid::knn_cell_size(p, 30), 30);
  expect_knn_like_tree(p, 0.002, 10);
}

TEST(VoxelGrid, KnnWithMoreNeighboursThanPointsReturnsAll) {
  const Points p = test::random_box_points(20, 3);
  expect_knn_like_tree(p, 0.1, 50);
  expect_knn_like_tree(p, 0.1, 0);
}

TEST(VoxelGrid, FarFromTheOriginEqualsTheKdTree) {
  const Points p = test::random_box_points(2000, 50, Eigen::Vector3d(4.2e6, -3.1e6, 1.0e3));
  expect_knn_like_tree(p, VoxelGrid::knn_cell_size(p, 16), 16);
  expect_radius_like_tree(p, 0.08, 0.08);
}

TEST(VoxelGrid, RadiusAndCountsEqualTheKdTree) {
  const Points p = test::random_box_points(3000, 200);
  expect_radius_like_tree(p, 0.05, 0.05);   // one ring
  expect_radius_like_tree(p, 0.05, 0.03);   // smaller than a cell
  expect_radius_like_tree(p, 0.02, 0.05);   // three rings
  expect_radius_like_tree(p, 0.05, 0.0);    // duplicates only
  expect_radius_like_tree(test::lattice_points(6), 1.0, 1.0);  // exactly on the radius: inclusive
  expect_radius_like_tree(uneven_points(), 0.2, 0.2);
}

TEST(VoxelGrid, CoincidentPoints) {
  const Points p(50, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(VoxelGrid::knn_cell_size(p, 10), 1.0);
  expect_knn_like_tree(p, 1.0, 10);
  expect_radius_like_tree(p, 1.0, 0.0);
}

TEST(VoxelGrid, GridOrderIsAPermutation) {
  const Points p = test::random_box_points(500, 0);
  const VoxelGrid grid(p, 0.1);
  std::vector<std::uint32_t> order(grid.grid_order().begin(), grid.grid_order().end());
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < order.size(); ++i) ASSERT_EQ(order[i], i);
  EXPECT_EQ(grid.size(), 500u);
  EXPECT_GT(grid.cells(), 100u);
  EXPECT_LE(grid.cells(), 1000u);
}

TEST(VoxelGrid, BadInputThrowsUsageError) {
  EXPECT_THROW(VoxelGrid(Points{}, 1.0), UsageError);
  EXPECT_THROW(VoxelGrid(test::random_box_points(10, 0), 0.0), UsageError);
  EXPECT_THROW(VoxelGrid(test::random_box_points(10, 0), std::nan("")), UsageError);
  EXPECT_THROW(VoxelGrid::knn_cell_size(Points{}, 3), UsageError);
  const VoxelGrid grid(test::random_box_points(10, 0), 0.5);
  EXPECT_THROW(grid.for_each_radius(-1.0, [](std::uint32_t, std::span<const Neighbor>) {}), UsageError);
  EXPECT_THROW(grid.count_within(std::nan(""), 3), UsageError);
}

}  // namespace
}  // namespace pointsurf
