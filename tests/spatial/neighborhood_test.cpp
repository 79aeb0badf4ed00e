// SPDX-License-Identifier: GPL-3.0-or-later
// The one neighbourhood type: its check, its radius and its query match the kd-tree's.
#include "pointsurf/spatial/neighborhood.h"

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/shape/curvature.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(Neighborhood, ChecksOnlyWhatItsKindUses) {
  test::expect_error<UsageError>([] { Neighborhood{.k = 2}.validate("f", 3); }, "f: k must be >= 3, got 2");
  EXPECT_NO_THROW((Neighborhood{.kind = NeighborhoodKind::Radius, .k = 2}.validate("f", 3)));
  EXPECT_NO_THROW((Neighborhood{.radius = Length::cloud(-1.0)}.validate("f", 3)));  // knn uses no radius
  test::expect_error<UsageError>([] { Neighborhood{.kind = NeighborhoodKind::Hybrid, .radius = Length::cloud(-1.0)}.validate("f", 3); },
                                 "f: radius must be > 0, got -1");
  test::expect_error<UsageError>([] { Neighborhood{.kind = NeighborhoodKind::Radius, .radius = Length::spacings(0.0)}.validate("f", 3); },
                                 "f: radius must be > 0, got 0sp");
}

TEST(Neighborhood, QueriesAsTheTreeDoesAndResolvesTheRadiusFromTheSpacing) {
  const PointCloud sphere = test::sample_sphere(2000);
  const KdTree tree(sphere.positions);
  const double spacing = mean_spacing(tree);
  std::vector<Neighbor> a, b;
  const Neighborhood knn{.k = 12};
  knn.query(tree, sphere.positions[5], 12, 0.0, a);
  tree.knn(sphere.positions[5], 12, b);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].index, b[i].index);
  const Neighborhood hybrid{.kind = NeighborhoodKind::Hybrid, .k = 8, .radius = Length::spacings(2.0)};
  EXPECT_DOUBLE_EQ(hybrid.resolve_radius(tree), 2.0 * spacing);
  EXPECT_EQ(knn.resolve_radius(tree), 0.0);
  hybrid.query(tree, sphere.positions[5], 8, 2.0 * spacing, a);
  tree.hybrid(sphere.positions[5], 8, 2.0 * spacing, b);
  EXPECT_EQ(a.size(), b.size());
  // normals and curvature hand their fields over as this one type
  EXPECT_EQ(NormalParams{}.neighborhood_settings().k, NormalParams{}.k);
  EXPECT_EQ(CurvatureParams{}.neighborhood_settings().k, 24);                   // k = 0: the degree's default
  EXPECT_EQ(CurvatureParams{.degree = 3}.neighborhood_settings().k, 40);
  EXPECT_EQ(CurvatureParams{}.neighborhood_settings().radius, CurvatureParams{}.radius);
}

}  // namespace
}  // namespace pointsurf
