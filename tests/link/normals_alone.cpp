// SPDX-License-Identifier: GPL-3.0-or-later
// A program that uses only normal estimation links only the modules normals needs (core,
// spatial, normals: see CMakeLists.txt): this file is linked with pointsurf::normals alone, so a
// use of a later module's code from core, spatial or normals fails to build. Its ctest entry
// also checks that no picture, XML or report library came along.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/normals/normals.h"

namespace pointsurf {
namespace {

TEST(NormalsAlone, SphereNormalsAreRadialWithOnlyTheNormalsModuleLinked) {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  PointCloud cloud;
  for (int i = 0; i < 2000; ++i) {
    Eigen::Vector3d p(g(rng), g(rng), g(rng));
    cloud.positions.push_back(2.0 * p.normalized());
  }
  NormalParams params;
  params.k = 16;
  const NormalResult r = estimate_normals(cloud, params);
  (void)r;
  ASSERT_EQ(cloud.normals.size(), cloud.positions.size());
  double worst = 1.0;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    worst = std::min(worst, std::abs(cloud.normals[i].dot(cloud.positions[i].normalized())));
  EXPECT_GT(worst, 0.99);
}

}  // namespace
}  // namespace pointsurf
