// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/segment/outlines.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

// A 2 x 2 square with a round hole of radius 0.4 at its centre, tilted and shifted, sampled
// uniformly (`n` points in the square before the hole is cut out), all labelled 0.
PointCloud square_with_hole(std::size_t n, const Eigen::Vector3d& shift) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  PointCloud cloud;
  while (cloud.positions.size() < n) {
    const double x = u(rng), y = u(rng);
    if (x * x + y * y < 0.4 * 0.4) continue;
    cloud.positions.push_back(rotation * Eigen::Vector3d(x, y, 0.0) + shift);
  }
  return cloud;
}

void check_square_with_hole(const Eigen::Vector3d& shift) {
  const PointCloud cloud = square_with_hole(40000, shift);
  const std::vector<std::int32_t> labels(cloud.size(), 0);
  const OutlineResult r = outline_planar_segments(cloud, labels);
  ASSERT_EQ(r.outlines.size(), 1u);
  const SegmentOutline& o = r.outlines[0];
  ASSERT_EQ(o.loops.size(), 2u);
  EXPECT_EQ(o.hole[0], 0);
  EXPECT_EQ(o.hole[1], 1);
  EXPECT_NEAR(o.loops[0].length(), 8.0, 0.02 * 8.0);
  EXPECT_NEAR(o.loops[1].length(), 2 * M_PI * 0.4, 0.02 * 2 * M_PI * 0.4);
  EXPECT_NEAR(o.area, 4.0 - M_PI * 0.16, 0.02 * (4.0 - M_PI * 0.16));
}

TEST(OutlinePlanarSegments, SquareWithARoundHoleHasOneOuterAndOneInnerLoop) { check_square_with_hole(Eigen::Vector3d::Zero()); }

TEST(OutlinePlanarSegments, SameFarFromTheOrigin) { check_square_with_hole(Eigen::Vector3d(1e6, -1e6, 1e6)); }

TEST(OutlinePlanarSegments, SkipsCurvedSegmentsAndChecksInput) {
  PointCloud sphere;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  for (int i = 0; i < 5000; ++i) {
    const double x = g(rng), y = g(rng), z = g(rng);
    sphere.positions.push_back(Eigen::Vector3d(x, y, z).normalized());
  }
  const std::vector<std::int32_t> labels(sphere.size(), 0);
  const OutlineResult r = outline_planar_segments(sphere, labels);
  EXPECT_TRUE(r.outlines.empty());
  EXPECT_EQ(r.nonplanar, 1u);
  EXPECT_THROW(outline_planar_segments(sphere, std::vector<std::int32_t>(3, 0)), UsageError);
  OutlineParams p;
  p.alpha = -1.0;
  EXPECT_THROW(p.validate(), UsageError);
  EXPECT_TRUE(outline_planar_segments(PointCloud{}, {}).outlines.empty());
}

}  // namespace
}  // namespace pointsurf
