// SPDX-License-Identifier: GPL-3.0-or-later
// The global sign of MST orientation on terrain: generated aerial tiles (ground, buildings with
// eaves, trees, a bridge deck) whose ground and roofs must face up, with and without a LAS
// classification; objects that must still face outward; the warning on a close vote.
#include <cstdio>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "pointsurf/normals/normals.h"
#include "support/scan_views.h"
#include "support/shapes.h"
#include "support/terrain_scene.h"

namespace pointsurf {
namespace {

// PCA normals with random signs (seeded), as orient_normals gets them from a file without normals.
void estimate_with_random_signs(PointCloud& cloud, std::uint64_t seed) {
  estimate_normals(cloud, {.k = 20});
  std::mt19937_64 coin(seed);
  for (Vector3d& n : cloud.normals)
    if (coin() & 1) n = -n;
}

struct TileCase {
  std::size_t trees;  // 12: scattered trees (3 % of the points); 300: a third of the points in crowns
  std::uint64_t seed;
};

std::string tile_case_name(const ::testing::TestParamInfo<TileCase>& info) {
  return "trees" + std::to_string(info.param.trees) + "_seed" + std::to_string(info.param.seed);
}

// With 300 trees, before issue 28 the outward vote decided these tiles on five seeds of eight
// (1, 3, 4, 6, 7): every ground normal down.
class OrientTerrainTile : public ::testing::TestWithParam<TileCase> {
protected:
  test::TerrainTile tile() const {
    test::TerrainTile t = test::sample_terrain_tile(40000, GetParam().seed, GetParam().trees);
    estimate_with_random_signs(t.cloud, GetParam().seed + 100);
    return t;
  }
  void expect_up(const test::TerrainTile& t, const OrientResult& r, const char* what) const {
    const double ground = test::share_up(t, t.cloud, test::kLasGround);
    const double roofs = test::share_up(t, t.cloud, test::kLasBuilding, 0.9);
    std::printf("%s, %zu trees, seed %llu: ground up %.4f, roofs up %.4f, %zu components\n", what, GetParam().trees,
                static_cast<unsigned long long>(GetParam().seed), ground, roofs, r.components);
    EXPECT_GE(ground, 0.99);
    EXPECT_GE(roofs, 0.98);
    EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  }
};

TEST_P(OrientTerrainTile, GroundAndRoofsFaceUp) {
  test::TerrainTile t = tile();
  const OrientResult r = orient_normals(t.cloud);
  expect_up(t, r, "geometry");
}

TEST_P(OrientTerrainTile, ClassifiedGroundFacesUp) {
  test::TerrainTile t = tile();
  t.cloud.fields.add("classification", 0, ScalarType::UInt8).values = t.truth;
  const OrientResult r = orient_normals(t.cloud);
  expect_up(t, r, "classified");
}

INSTANTIATE_TEST_SUITE_P(Tiles, OrientTerrainTile,
                         ::testing::Values(TileCase{12, 1}, TileCase{12, 2}, TileCase{12, 3}, TileCase{12, 4}, TileCase{12, 5},
                                           TileCase{300, 1}, TileCase{300, 2}, TileCase{300, 3}, TileCase{300, 4},
                                           TileCase{300, 5}, TileCase{300, 6}, TileCase{300, 7}, TileCase{300, 8}),
                         tile_case_name);

// The same with the tile moved far away and its points permuted: the columns are binned
// relative to each component, and the vote does not depend on the order.
TEST(OrientTerrain, PermutedTileFarAwayFacesUp) {
  test::TerrainTile t = test::sample_terrain_tile(40000, 3, 300);
  std::vector<std::size_t> order(t.cloud.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937_64(9));
  test::TerrainTile moved;
  moved.cloud = t.cloud.select(order);
  for (std::size_t i : order) {
    moved.exact.push_back(t.exact[i]);
    moved.truth.push_back(t.truth[i]);
  }
  for (Vector3d& p : moved.cloud.positions) p += Vector3d(3e6, -2e6, 500.0);
  estimate_with_random_signs(moved.cloud, 4);
  orient_normals(moved.cloud);
  EXPECT_GE(test::share_up(moved, moved.cloud, test::kLasGround), 0.99);
  EXPECT_GE(test::share_up(moved, moved.cloud, test::kLasBuilding, 0.9), 0.98);
}

// Closed objects and the kitten scan keep facing outward, without a warning.
TEST(OrientTerrain, ObjectsStillFaceOutward) {
  PointCloud sphere = test::sample_sphere(20000, 1.5, Vector3d(0.3, -0.2, 0.1), 3);
  const std::vector<Vector3d> exact = sphere.normals;
  estimate_with_random_signs(sphere, 5);
  OrientResult r = orient_normals(sphere);
  EXPECT_EQ(compare_normals(exact, sphere.normals).share, 1.0);
  EXPECT_TRUE(r.warnings.empty());

  PointCloud kitten = test::kitten();
  const std::vector<Vector3d> scanned = kitten.normals;
  kitten.normals.clear();
  estimate_with_random_signs(kitten, 6);
  r = orient_normals(kitten);
  const NormalAgreement agreement = compare_normals(scanned, kitten.normals);
  std::printf("kitten: %.4f of the normals on the side of the file's\n", agreement.share);
  EXPECT_GE(agreement.share, 0.99);
  EXPECT_TRUE(r.warnings.empty());
}

// A single vertical wall has no inside and no up: its sign is a coin toss, and said so.
TEST(OrientTerrain, CloseVoteOnAWallIsWarned) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  PointCloud wall;
  for (int i = 0; i < 5000; ++i) {
    const double y = u(rng), z = u(rng);
    wall.positions.emplace_back(0.002 * std::sin(3.0 * y), y, z);
  }
  estimate_with_random_signs(wall, 8);
  const OrientResult r = orient_normals(wall);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("orient mst: close vote on the sign of a component of 5000 points"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("for facing outward"), std::string::npos) << r.warnings[0];
}

}  // namespace
}  // namespace pointsurf
