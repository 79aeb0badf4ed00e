// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/clean/remove_duplicates.h"

#include <algorithm>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::expect_error;

// 2000 points of a plane, then copies of points 0..99 appended: exact copies of 0..49 and
// copies of 50..99 moved by `offset` along x.
PointCloud with_copies(double offset) {
  PointCloud cloud = test::sample_plane(2000, 1.0, 4);
  cloud.colors.assign(cloud.size(), Vector3f(0.0f, 0.0f, 0.0f));
  ScalarField& label = cloud.fields.add("label", cloud.size(), ScalarType::UInt8);
  std::fill(label.values.begin(), label.values.end(), 1.0);
  std::vector<std::size_t> first(100);
  std::iota(first.begin(), first.end(), std::size_t(0));
  PointCloud copies = cloud.select(first);
  for (std::size_t i = 0; i < 100; ++i) {
    if (i >= 50) copies.positions[i].x() += offset;
    copies.colors[i] = Vector3f(1.0f, 1.0f, 1.0f);
    copies.normals[i] = -copies.normals[i];  // opposite side: must not cancel the average
    copies.fields.find("label")->values[i] = 7.0;
  }
  cloud.append(copies);
  return cloud;
}

TEST(Duplicates, ExactCopiesMergeIntoTheFirstPoint) {
  PointCloud cloud = with_copies(1e-3);
  const DuplicateResult found = find_duplicates(cloud, {.exact = true});
  EXPECT_EQ(found.removed, 50u);
  EXPECT_EQ(found.distance_used, 0.0);
  EXPECT_EQ(found.max_distance, 0.0);
  ASSERT_EQ(found.representative.size(), cloud.size());
  for (std::uint32_t i = 0; i < 50; ++i) EXPECT_EQ(found.representative[2000 + i], i);
  for (std::uint32_t i = 50; i < 100; ++i) EXPECT_EQ(found.representative[2000 + i], 2000 + i);
  const PointCloud merged = merge_duplicates(cloud, found);
  ASSERT_EQ(merged.size(), cloud.size() - 50);
  EXPECT_EQ(merged.positions[3], cloud.positions[3]);
  EXPECT_EQ(merged.normals[3], cloud.normals[3]);                      // average of n and -(-n)
  EXPECT_TRUE(merged.colors[3].isApprox(Vector3f(0.5f, 0.5f, 0.5f)));  // colours averaged
  EXPECT_EQ(merged.fields.find("label")->values[3], 1.0);              // labels of the kept point
  EXPECT_EQ(merged.colors[100], Vector3f(0.0f, 0.0f, 0.0f));           // not a duplicate: unchanged
}

TEST(Duplicates, NearCopiesWithinTheDefaultDistance) {
  PointCloud probe = test::sample_plane(2000, 1.0, 4);
  const double spacing = mean_spacing(probe.positions);
  PointCloud cloud = with_copies(0.02 * spacing);
  const DuplicateResult found = remove_duplicates(cloud);
  EXPECT_NEAR(found.distance_used, 0.1 * mean_spacing(with_copies(0.02 * spacing).positions), 1e-15);
  EXPECT_GE(found.removed, 100u);
  EXPECT_LE(found.removed, 110u);  // a few sample pairs of the plane may be that close too
  EXPECT_LE(found.max_distance, found.distance_used);
  EXPECT_EQ(cloud.size(), 2100u - found.removed);
  // No two kept points closer than the distance.
  const KdTree tree(cloud.positions);
  std::vector<Neighbor> nb;
  for (const Vector3d& p : cloud.positions) {
    tree.knn(p, 2, nb);
    EXPECT_GT(std::sqrt(nb[1].squared_distance), found.distance_used);
  }
}

TEST(Duplicates, KeepsTheFirstOfAChainByIndex) {
  PointCloud cloud;
  cloud.positions = {Vector3d(0, 0, 0), Vector3d(0.9, 0, 0), Vector3d(1.8, 0, 0), Vector3d(5, 0, 0)};
  const DuplicateResult found = find_duplicates(cloud, {.distance = Length::cloud(1.0)});
  // 1 merges into 0; 2 is 1.8 from 0 (the only earlier kept point), so it is kept.
  EXPECT_EQ(found.kept, (std::vector<std::uint32_t>{0, 2, 3}));
  EXPECT_EQ(found.representative, (std::vector<std::uint32_t>{0, 0, 2, 3}));
  EXPECT_NEAR(found.max_distance, 0.9, 1e-12);
}

TEST(Duplicates, ExactCountInvariantUnderPermutationAndAFarShift) {
  PointCloud cloud = with_copies(1e-3);
  const std::size_t removed = find_duplicates(cloud, {.exact = true}).removed;
  std::vector<std::size_t> perm(cloud.size());
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(3));
  EXPECT_EQ(find_duplicates(cloud.select(perm), {.exact = true}).removed, removed);
  const std::size_t near = find_duplicates(cloud, {.distance = Length::cloud(2e-3)}).removed;
  EXPECT_GE(near, 100u);
  for (Vector3d& p : cloud.positions) p += Vector3d(2e6, 5e6, 100.0);
  EXPECT_EQ(find_duplicates(cloud, {.exact = true}).removed, removed);
  EXPECT_EQ(find_duplicates(cloud, {.distance = Length::cloud(2e-3)}).removed, near);
}

TEST(Duplicates, BadParametersAreUsageErrors) {
  PointCloud cloud = test::sample_plane(20);
  expect_error<UsageError>([&] { find_duplicates(cloud, {.distance = Length::cloud(-1.0)}); }, "find_duplicates: distance must be > 0, got -1");
  expect_error<UsageError>([&] { find_duplicates(cloud, {.distance = Length::spacings(-2.0)}); }, "distance must be > 0, got -2sp");
  expect_error<UsageError>([&] { find_duplicates(PointCloud{}); }, "find_duplicates: needs at least 1 points, got 0");
  DuplicateResult found = find_duplicates(cloud);
  found.representative.pop_back();
  expect_error<UsageError>([&] { merge_duplicates(cloud, found); }, "merge_duplicates: the result covers 19 points but the cloud has 20");
  EXPECT_THROW(find_duplicates(cloud, {}, nullptr, [](double) { return false; }), CancelledError);
}

}  // namespace
}  // namespace pointsurf
