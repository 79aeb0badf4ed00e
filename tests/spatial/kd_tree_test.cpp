// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/spatial/kd_tree.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using Points = std::vector<Eigen::Vector3d>;

// Brute force: every point with its squared distance, nearest first, ties by index.
std::vector<Neighbor> brute_force(const Points& points, const Eigen::Vector3d& q) {
  std::vector<Neighbor> all;
  for (std::size_t i = 0; i < points.size(); ++i)
    all.push_back(Neighbor{static_cast<std::uint32_t>(i), (points[i] - q).squaredNorm()});
  std::sort(all.begin(), all.end(), [](const Neighbor& a, const Neighbor& b) {
    return a.squared_distance < b.squared_distance || (a.squared_distance == b.squared_distance && a.index < b.index);
  });
  return all;
}

std::vector<Neighbor> brute_knn(const Points& points, const Eigen::Vector3d& q, std::size_t k) {
  std::vector<Neighbor> all = brute_force(points, q);
  all.resize(std::min(k, all.size()));
  return all;
}

std::vector<Neighbor> brute_radius(const Points& points, const Eigen::Vector3d& q, double r, std::size_t k = SIZE_MAX) {
  std::vector<Neighbor> all = brute_force(points, q);
  std::vector<Neighbor> out;
  for (const Neighbor& n : all)
    if (n.squared_distance <= r * r && out.size() < k) out.push_back(n);
  return out;
}

// Same indices in the same order, distances equal to a relative 1e-9 of the scale.
void expect_same(std::span<const Neighbor> got, std::span<const Neighbor> want, double scale = 1.0) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].index, want[i].index) << "position " << i;
    EXPECT_NEAR(got[i].squared_distance, want[i].squared_distance, 1e-9 * scale) << "position " << i;
  }
}

TEST(KdTree, KnnMatchesBruteForceWithDuplicates) {
  const Points points = test::random_box_points(1500, 300);
  const KdTree tree(points);
  ASSERT_EQ(tree.size(), points.size());
  const Points queries = test::random_box_points(40, 0, Eigen::Vector3d::Constant(-0.1), 11);
  std::vector<Neighbor> out;
  for (std::size_t k : {std::size_t(1), std::size_t(2), std::size_t(8), std::size_t(30)}) {
    for (const Eigen::Vector3d& q : queries) {
      tree.knn(q, k, out);
      expect_same(out, brute_knn(points, q, k));
    }
    for (std::size_t i = 0; i < points.size(); i += 37) {
      tree.knn(points[i], k, out);
      expect_same(out, brute_knn(points, points[i], k));
    }
  }
}

TEST(KdTree, KnnWithKAboveSizeReturnsEveryPoint) {
  const Points points = test::random_box_points(20, 5);
  const KdTree tree(points);
  std::vector<Neighbor> out;
  tree.knn(Eigen::Vector3d(0.5, 0.5, 0.5), 1000, out);
  expect_same(out, brute_force(points, Eigen::Vector3d(0.5, 0.5, 0.5)));
  tree.knn(Eigen::Vector3d::Zero(), 0, out);
  EXPECT_TRUE(out.empty());
}

TEST(KdTree, TiesAreBrokenByIndex) {
  const Points points = test::lattice_points(6);
  const KdTree tree(points, 3);
  std::vector<Neighbor> out;
  for (std::size_t i = 0; i < points.size(); i += 5) {
    for (std::size_t k : {std::size_t(1), std::size_t(4), std::size_t(7), std::size_t(12)}) {
      tree.knn(points[i], k, out);
      expect_same(out, brute_knn(points, points[i], k));
      tree.hybrid(points[i], k, 1.0, out);
      expect_same(out, brute_radius(points, points[i], 1.0, k));
    }
    tree.radius(points[i], 1.5, out);
    expect_same(out, brute_radius(points, points[i], 1.5));
  }
}

TEST(KdTree, RadiusAndHybridMatchBruteForce) {
  const Points points = test::random_box_points(1500, 300);
  const KdTree tree(points);
  const Points queries = test::random_box_points(40, 0, Eigen::Vector3d::Zero(), 12);
  std::vector<Neighbor> out;
  for (double r : {0.0, 0.02, 0.1, 0.3}) {
    for (const Eigen::Vector3d& q : queries) {
      tree.radius(q, r, out);
      expect_same(out, brute_radius(points, q, r));
      tree.hybrid(q, 10, r, out);
      expect_same(out, brute_radius(points, q, r, 10));
    }
  }
}

TEST(KdTree, RadiusZeroFindsExactDuplicates) {
  Points points = test::random_box_points(200, 0);
  points.push_back(points[17]);
  points.push_back(points[17]);
  const KdTree tree(points);
  std::vector<Neighbor> out;
  tree.radius(points[17], 0.0, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].index, 17u);
  EXPECT_EQ(out[1].index, 200u);
  EXPECT_EQ(out[2].index, 201u);
  for (const Neighbor& n : out) EXPECT_EQ(n.squared_distance, 0.0);
}

TEST(KdTree, RadiusIsInclusive) {
  const Points points = test::lattice_points(3, 0.25);  // distances 0.25 are exact in binary
  const KdTree tree(points);
  std::vector<Neighbor> out;
  tree.radius(points[13], 0.25, out);  // the centre and its 6 face neighbours
  EXPECT_EQ(out.size(), 7u);
  tree.hybrid(points[13], 100, 0.25, out);
  EXPECT_EQ(out.size(), 7u);
}

TEST(KdTree, GeoreferencedCloudKeepsPrecision) {
  const Eigen::Vector3d offset(6.5e6, -4.3e6, 6.5e6);
  const Points points = test::random_box_points(1000, 50, offset);
  const Points local = test::random_box_points(1000, 50);
  const KdTree tree(points);
  std::vector<Neighbor> out;
  for (std::size_t i = 0; i < points.size(); i += 29) {
    tree.knn(points[i], 10, out);
    // Indices as in the unshifted cloud, squared distances to ~1e-9 of the cloud's scale.
    expect_same(out, brute_knn(local, local[i], 10), 1.0);
    tree.radius(points[i], 0.1, out);
    expect_same(out, brute_radius(local, local[i], 0.1), 1.0);
    EXPECT_EQ(tree.point(i), points[i]);
  }
  // Two points 0.1 mm apart at 6.5e6 m: the distance is as exact as their stored coordinates
  // (which are 1e-4 only to within their ulp, 9e-10 m).
  const Points pair{offset, offset + Eigen::Vector3d(1e-4, 0, 0)};
  const KdTree small(pair);
  small.knn(pair[0], 2, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_DOUBLE_EQ(std::sqrt(out[1].squared_distance), (pair[1] - pair[0]).norm());
  EXPECT_NEAR(std::sqrt(out[1].squared_distance), 1e-4, 1e-9);
}

TEST(KdTree, BatchQueriesEqualSingleQueries) {
  const Points points = test::random_box_points(3000, 200);
  const KdTree tree(points);
  const Points queries = test::random_box_points(500, 0, Eigen::Vector3d::Zero(), 21);
  std::vector<Neighbor> out;
  for (const Points* qs : {&points, &queries}) {
    const bool own = qs == &points;
    const std::span<const Eigen::Vector3d> arg = own ? std::span<const Eigen::Vector3d>{} : *qs;
    const NeighborLists knn = tree.knn_all(arg, 12);
    const NeighborLists radius = tree.radius_all(arg, 0.06);
    const NeighborLists hybrid = tree.hybrid_all(arg, 12, 0.06);
    ASSERT_EQ(knn.size(), qs->size());
    ASSERT_EQ(radius.size(), qs->size());
    ASSERT_EQ(hybrid.size(), qs->size());
    for (std::size_t i = 0; i < qs->size(); ++i) {
      tree.knn((*qs)[i], 12, out);
      expect_same(knn[i], out);
      tree.radius((*qs)[i], 0.06, out);
      expect_same(radius[i], out);
      tree.hybrid((*qs)[i], 12, 0.06, out);
      expect_same(hybrid[i], out);
    }
  }
}

TEST(KdTree, ConcurrentQueriesGiveTheSameAnswers) {
  const Points points = test::random_box_points(4000, 100);
  const KdTree tree(points);
  const NeighborLists reference = tree.knn_all({}, 9);
  std::vector<int> mismatches(4, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      std::vector<Neighbor> out;
      for (std::size_t i = static_cast<std::size_t>(t); i < points.size(); i += 2) {
        tree.knn(points[i], 9, out);
        const auto want = reference[i];
        if (out.size() != want.size() || !std::equal(out.begin(), out.end(), want.begin(), [](const Neighbor& a, const Neighbor& b) {
              return a.index == b.index && a.squared_distance == b.squared_distance;
            }))
          ++mismatches[t];
      }
    });
  }
  for (std::thread& th : threads) th.join();
  for (int t = 0; t < 4; ++t) EXPECT_EQ(mismatches[t], 0) << "thread " << t;
}

TEST(KdTree, MovedTreeStillAnswers) {
  const Points points = test::random_box_points(100, 0);
  KdTree a(points);
  KdTree b(std::move(a));
  std::vector<Neighbor> out;
  b.knn(points[5], 3, out);
  expect_same(out, brute_knn(points, points[5], 3));
}

TEST(KdTree, BadInputThrowsUsageError) {
  const Points none;
  try {
    KdTree tree(none);
    FAIL() << "expected UsageError";
  } catch (const UsageError& e) {
    EXPECT_EQ(std::string(e.what()), "KdTree: cannot build a tree over an empty point set");
  }
  const Points points = test::random_box_points(10, 0);
  EXPECT_THROW(KdTree(points, 0), UsageError);
  const KdTree tree(points);
  std::vector<Neighbor> out;
  try {
    tree.radius(points[0], -1.0, out);
    FAIL() << "expected UsageError";
  } catch (const UsageError& e) {
    EXPECT_EQ(std::string(e.what()), "KdTree::radius: radius must be >= 0, got -1");
  }
  EXPECT_THROW(tree.hybrid(points[0], 3, -0.5, out), UsageError);
  EXPECT_THROW(tree.radius_all({}, -0.5), UsageError);
}

TEST(MeanSpacing, RegularGridGivesTheGridStep) {
  const double h = 0.125;
  Points grid = test::lattice_points(12, h, Eigen::Vector3d(6.5e6, 1e6, 300.0));
  EXPECT_NEAR(mean_spacing(grid), h, 1e-9);
  const std::size_t n = grid.size();
  for (std::size_t i = 0; i < n; i += 3) grid.push_back(grid[i]);  // duplicates do not count
  for (std::size_t i = 0; i < n; i += 7) grid.push_back(grid[i]);
  EXPECT_NEAR(mean_spacing(grid), h, 1e-9);
  EXPECT_NEAR(mean_spacing(grid, 50, 9), h, 1e-9);  // a sample of 50 points
  // A stack of 30,000 copies of one grid point: each copy's nearest distinct point is one step
  // away, found once for the whole stack (a query per copy would step over the stack each time).
  for (int i = 0; i < 30000; ++i) grid.push_back(grid[5]);
  EXPECT_NEAR(mean_spacing(grid), h, 1e-9);
}

TEST(MeanSpacing, SampleIsSeededAndCoincidentPointsGiveZero) {
  const Points points = test::random_box_points(3000, 0);
  const KdTree tree(points);
  EXPECT_EQ(mean_spacing(tree, 500, 1), mean_spacing(tree, 500, 1));
  EXPECT_NEAR(mean_spacing(tree, 500, 1), mean_spacing(tree), 0.1 * mean_spacing(tree));
  const Points same(5, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(mean_spacing(same), 0.0);
  try {
    mean_spacing(Points{Eigen::Vector3d::Zero()});
    FAIL() << "expected UsageError";
  } catch (const UsageError& e) {
    EXPECT_EQ(std::string(e.what()), "mean_spacing: needs at least 2 points, got 1");
  }
  EXPECT_THROW(mean_spacing(tree, 0), UsageError);
}

TEST(MortonOrder, IsAPermutationInZOrder) {
  // The unit cube's corners: the Z-order key is x + 2y + 4z.
  Points corners;
  for (int i = 7; i >= 0; --i) corners.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  const std::vector<std::uint32_t> order = morton_order(corners);
  ASSERT_EQ(order.size(), 8u);
  for (std::size_t pos = 0; pos < 8; ++pos) EXPECT_EQ(order[pos], 7 - pos);

  const Points points = test::random_box_points(5000, 100);
  std::vector<std::uint32_t> perm = morton_order(points);
  std::sort(perm.begin(), perm.end());
  for (std::size_t i = 0; i < perm.size(); ++i) ASSERT_EQ(perm[i], i);
  EXPECT_TRUE(morton_order(Points{}).empty());
  EXPECT_EQ(morton_order(Points(3, Eigen::Vector3d::Ones())).size(), 3u);
}

}  // namespace
}  // namespace pointsurf
