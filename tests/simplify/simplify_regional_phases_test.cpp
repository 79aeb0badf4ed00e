// SPDX-License-Identifier: GPL-3.0-or-later
// The phases of simplify_regional (simplify/detail/regional_simplification.h), each run alone on
// a small cloud or on hand-made state whose answer is known by construction.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>

#include <gtest/gtest.h>

#include "pointsurf/simplify/simplify.h"
#include "simplify/detail/regional_simplification.h"

namespace pointsurf {
namespace {

using detail::ProgressReporter;
using detail::RegionalSimplification;

constexpr double kStep = 0.05;

// An L: a floor (z = 0, x > 0, normals +z) and a wall (x = 0, z > 0, normals +x), 20 x 20 points
// each at kStep, with zero surface variation given. Floor points come first.
PointCloud make_l() {
  PointCloud c;
  for (int i = 1; i <= 20; ++i)
    for (int j = 0; j < 20; ++j) c.positions.emplace_back(kStep * i, kStep * j, 0.0), c.normals.push_back(Vector3d::UnitZ());
  for (int k = 1; k <= 20; ++k)
    for (int j = 0; j < 20; ++j) c.positions.emplace_back(0.0, kStep * j, kStep * k), c.normals.push_back(Vector3d::UnitX());
  c.fields.add("variation", c.size()).values.assign(c.size(), 0.0);
  return c;
}

// One region cell over the whole L, the spacing given.
RegionalParams l_params() {
  RegionalParams p;
  p.region_size = Length::cloud(10.0);
  p.spacing = kStep;
  return p;
}

// A line of `n` points x = 0, 1, ... with normals +z.
PointCloud make_line(std::size_t n) {
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) c.positions.emplace_back(double(i), 0.0, 0.0), c.normals.push_back(Vector3d::UnitZ());
  return c;
}

const ProgressCallback kNoProgress;

TEST(SimplifyRegionalPhases, NormalClassesAreTheFacesOfACubeMap) {
  EXPECT_EQ(detail::normal_class(Vector3d::Zero()), 27u);
  EXPECT_EQ(detail::normal_class(Vector3d::UnitZ()), detail::normal_class(-Vector3d::UnitZ()));  // unoriented
  EXPECT_EQ(detail::normal_class(Vector3d::UnitZ()), 2u * 9 + 1 * 3 + 1);  // axis z, both others in the middle bin
  EXPECT_NE(detail::normal_class(Vector3d::UnitX()), detail::normal_class(Vector3d::UnitZ()));
  EXPECT_EQ(detail::normal_class(Vector3d(0.05, 0.0, 1.0).normalized()), detail::normal_class(Vector3d::UnitZ()));
}

TEST(SimplifyRegionalPhases, MeasureSurfaceTakesTheGivenNormalsVariationAndSpacing) {
  const PointCloud c = make_l();
  const RegionalParams p = l_params();
  RegionalSimplification x(c, p);
  x.measure_surface(nullptr, kNoProgress);
  EXPECT_EQ(x.spacing, kStep);
  EXPECT_EQ(x.surface.normals, c.normals);
  EXPECT_EQ(x.surface.variation, std::vector<double>(c.size(), 0.0));
  EXPECT_EQ(x.box.min, Vector3d(Vector3d::Zero()));
  ASSERT_NE(x.t, nullptr);
}

TEST(SimplifyRegionalPhases, ClusterRegionsSplitsTheLIntoItsTwoFaces) {
  const PointCloud c = make_l();
  const RegionalParams p = l_params();
  RegionalSimplification x(c, p);
  x.measure_surface(nullptr, kNoProgress);
  ProgressReporter reporter(kNoProgress, 0.6, 1.0, c.size());
  x.cluster_regions(reporter);
  ASSERT_EQ(x.planes.size(), 1u);  // one region cell
  ASSERT_EQ(x.planes[0].size(), 2u);
  std::set<int> axes;
  for (const detail::ClusterPlane& plane : x.planes[0]) {
    int axis = 0;
    EXPECT_DOUBLE_EQ(plane.normal.cwiseAbs().maxCoeff(&axis), 1.0);
    axes.insert(axis);
  }
  EXPECT_EQ(axes, (std::set<int>{0, 2}));
  for (std::uint32_t i = 0; i < c.size(); ++i) {
    const bool floor = i < 400;
    EXPECT_EQ(Vector3d(x.cluster_normal[i].cwiseAbs()), Vector3d(floor ? Vector3d::UnitZ() : Vector3d::UnitX()));
    EXPECT_EQ(x.cluster_key[i], detail::normal_class(floor ? Vector3d::UnitZ() : Vector3d::UnitX()));
    EXPECT_EQ(x.base_terms[i], 0.0f);  // no variation, normals along their cluster's
    EXPECT_EQ(x.own_delta[i], 0.0f);   // on their cluster's plane
  }
  std::vector<std::uint32_t> sorted = x.visit_order;
  std::sort(sorted.begin(), sorted.end());
  for (std::uint32_t i = 0; i < c.size(); ++i) ASSERT_EQ(sorted[i], i);
  EXPECT_TRUE(std::is_sorted(x.visit_order.begin(), x.visit_order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return std::lexicographical_compare(c.positions[a].data(), c.positions[a].data() + 3, c.positions[b].data(), c.positions[b].data() + 3);
  }));
}

TEST(SimplifyRegionalPhases, FindCreasesRisesLinearlyTowardsTheOtherFace) {
  const PointCloud c = make_l();
  const RegionalParams p = l_params();
  RegionalSimplification x(c, p);
  x.measure_surface(nullptr, kNoProgress);
  ProgressReporter reporter(kNoProgress, 0.6, 1.0, c.size());
  x.cluster_regions(reporter);
  x.find_creases(reporter);
  const double scale = 2.0 * kStep;  // the crease band: two spacings
  for (std::uint32_t i = 0; i < c.size(); ++i) {
    // A floor point's distance to the wall is x, a wall point's to the floor z.
    const double to_other = i < 400 ? c.positions[i].x() : c.positions[i].z();
    const double expected = std::max(0.0, 1.0 - to_other / scale);
    EXPECT_NEAR(x.crease[i], expected, 1e-6) << i;
    EXPECT_NEAR(x.factor[i], expected / 3.0, 1e-6) << i;  // the distance term of three equal weights
  }
}

TEST(SimplifyRegionalPhases, ChooseThresholdIsMedianPlusThreeMad) {
  const PointCloud c = make_line(5);
  RegionalParams p;
  RegionalSimplification x(c, p);
  x.factor = {0.5f, 0.1f, 0.4f, 0.2f, 0.3f};  // median 0.3, MAD 0.1
  x.choose_threshold();
  EXPECT_NEAR(x.threshold, 0.3 + 3.0 * 1.4826 * 0.1, 1e-6);
  x.factor = {0.0f, 0.0f, 1.0f, 0.0f, 0.0f};  // median 0, MAD 0: the floor
  x.choose_threshold();
  EXPECT_EQ(x.threshold, 0.02);
  RegionalParams given;
  given.feature_threshold = 0.7;
  RegionalSimplification y(c, given);
  y.factor = x.factor;
  y.choose_threshold();
  EXPECT_EQ(y.threshold, 0.7);
}

TEST(SimplifyRegionalPhases, SelectFeaturesKeepsTheBudgetByPriority) {
  PointCloud c = make_line(10);
  RegionalParams p;
  p.target.count = 4;  // a budget of max_feature_share 0.5 x 4 = 2 feature points
  {
    RegionalSimplification x(c, p);
    x.factor.resize(10), x.crease.assign(10, 0.0f);
    for (std::uint32_t i = 0; i < 10; ++i) x.factor[i] = float(i) / 10.0f;
    x.threshold = 0.45;  // candidates 5 .. 9
    x.select_features();
    EXPECT_EQ(x.candidates, (std::vector<std::uint32_t>{8, 9}));
    EXPECT_EQ(x.out.feature_points, 2u);
    EXPECT_EQ(x.wanted, 4u);
  }
  c.fields.add("feature", 10).values[1] = 1.0;  // marked by the features module: first
  RegionalSimplification x(c, p);
  x.factor.resize(10), x.crease.assign(10, 0.0f);
  for (std::uint32_t i = 0; i < 10; ++i) x.factor[i] = float(i) / 10.0f;
  x.threshold = 0.45;
  x.select_features();
  EXPECT_EQ(x.candidates, (std::vector<std::uint32_t>{1, 9}));
}

// A flat 20 x 20 grid at kStep in one normal class, no feature points, its state set by hand.
struct FlatGrid {
  PointCloud cloud;
  RegionalParams params;
  FlatGrid() {
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 20; ++j) cloud.positions.emplace_back(kStep * i, kStep * j, 0.0), cloud.normals.push_back(Vector3d::UnitZ());
  }
  void set_up(RegionalSimplification& x) const {
    const std::size_t n = cloud.size();
    x.box = bounding_box(cloud.positions);
    x.spacing = kStep;
    x.visit_order.resize(n);
    std::iota(x.visit_order.begin(), x.visit_order.end(), 0u);
    x.cluster_key.assign(n, detail::normal_class(Vector3d::UnitZ()));
    x.factor.assign(n, 0.0f), x.crease.assign(n, 0.0f);
    x.boundary.boundary.assign(n, 0);
    x.by_cell = params.target.cell > 0.0;
    x.wanted = x.by_cell ? 0 : detail::target_count(params.target, n);
  }
};

TEST(SimplifyRegionalPhases, ThinFlatAreasKeepsOnePointPerCell) {
  FlatGrid g;
  g.params.target.cell = 0.25;  // x, y in [0, 0.95]: 4 x 4 cells of 5 x 5 points
  RegionalSimplification x(g.cloud, g.params);
  g.set_up(x);
  ProgressReporter reporter(kNoProgress, 0.6, 1.0, g.cloud.size());
  x.thin_flat_areas(reporter);
  EXPECT_EQ(x.flat.size(), g.cloud.size());
  EXPECT_EQ(x.out.length_used, 0.25);
  std::set<std::pair<int, int>> cells;
  for (std::uint32_t i = 0; i < g.cloud.size(); ++i)
    if (x.kept_mask[i]) {
      const Vector3d& q = g.cloud.positions[i];
      EXPECT_TRUE(cells.insert({int(std::floor(q.x() / 0.25)), int(std::floor(q.y() / 0.25))}).second);
      // The cell's middle point (of 5 x 5) is nearest its centroid.
      EXPECT_NEAR(std::fmod(q.x(), 0.25), 2 * kStep, 1e-9);
      EXPECT_NEAR(std::fmod(q.y(), 0.25), 2 * kStep, 1e-9);
    }
  EXPECT_EQ(cells.size(), 16u);
}

TEST(SimplifyRegionalPhases, ThinFlatAreasAndTopUpReachTheCountExactly) {
  FlatGrid g;
  g.params.target.count = 30;
  RegionalSimplification x(g.cloud, g.params);
  g.set_up(x);
  ProgressReporter reporter(kNoProgress, 0.6, 1.0, g.cloud.size());
  x.thin_flat_areas(reporter);
  EXPECT_LE(std::count(x.kept_mask.begin(), x.kept_mask.end(), char(1)), 30);
  x.top_up();
  EXPECT_EQ(std::count(x.kept_mask.begin(), x.kept_mask.end(), char(1)), 30);
  const SimplifyResult r = std::move(x).result();
  EXPECT_EQ(r.cloud.size(), 30u);
  EXPECT_TRUE(std::is_sorted(r.source_index.begin(), r.source_index.end()));
}

TEST(SimplifyRegionalPhases, TopUpAddsTheLeftoverPointsOfHighestFactor) {
  const PointCloud c = make_line(10);
  RegionalParams p;
  p.target.count = 5;
  RegionalSimplification x(c, p);
  x.factor.resize(10), x.crease.assign(10, 0.0f);
  for (std::uint32_t i = 0; i < 10; ++i) x.factor[i] = float(i) / 10.0f;
  x.wanted = 5;
  x.kept_mask.assign(10, 0);
  x.kept_mask[0] = x.kept_mask[9] = 1;
  x.top_up();
  std::vector<std::uint32_t> kept;
  for (std::uint32_t i = 0; i < 10; ++i)
    if (x.kept_mask[i]) kept.push_back(i);
  EXPECT_EQ(kept, (std::vector<std::uint32_t>{0, 6, 7, 8, 9}));
}

}  // namespace
}  // namespace pointsurf
