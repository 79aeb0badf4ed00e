// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/spatial/voronoi_poles.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/crust_sampling.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

// Distance from x to the core circle (radius `major` in the xy plane) of a torus.
double core_distance(const Vector3d& x, double major) { return std::hypot(std::hypot(x.x(), x.y()) - major, x.z()); }

TEST(VoronoiPoles, SphereSamplesHaveTheirInnerPoleAtTheCentreAndAnOutwardAxis) {
  const PointCloud cloud = test::thin_poisson(test::sample_sphere(20000, 2.0, Vector3d::Zero(), 3), 0.12);
  const VoronoiPoles poles = voronoi_poles(cloud.positions);
  ASSERT_EQ(poles.negative.size(), cloud.size());
  EXPECT_EQ(poles.hull_points, cloud.size());  // every sample of a sphere is on its convex hull
  double worst_centre = 0.0, worst_axis = 1.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_FALSE(poles.positive[i].allFinite());  // p+ at infinity
    ASSERT_TRUE(poles.negative[i].allFinite()) << i;
    worst_centre = std::max(worst_centre, poles.negative[i].norm());
    worst_axis = std::min(worst_axis, poles.axis[i].dot(cloud.positions[i].normalized()));
  }
  // The medial axis of a sphere is its centre: the local feature size is the radius.
  EXPECT_LT(worst_centre, 0.1 * 2.0);
  EXPECT_GT(worst_axis, std::cos(10.0 * 3.14159265358979 / 180.0));
}

TEST(VoronoiPoles, TorusPolesApproximateTheCoreCircle) {
  const double major = 1.0, minor = 0.35;
  const PointCloud cloud = test::thin_poisson(test::sample_torus(80000, major, minor, 7), 0.04);
  const VoronoiPoles poles = voronoi_poles(cloud.positions);
  // Each sample's pole inside the tube lies near the core circle (the inner medial axis), at
  // distance ~ minor from the sample: LFS = minor wherever the inner part of the medial axis is
  // nearer, i.e. everywhere on this torus.
  std::size_t near_core = 0;
  double worst_lfs_error = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    double best = INFINITY, lfs = INFINITY;
    for (const Vector3d& pole : {poles.positive[i], poles.negative[i]})
      if (pole.allFinite() && core_distance(pole, major) < best) {
        best = core_distance(pole, major);
        lfs = (pole - cloud.positions[i]).norm();
      }
    if (best < 0.1 * minor) {
      ++near_core;
      worst_lfs_error = std::max(worst_lfs_error, std::abs(lfs - minor));
    }
  }
  EXPECT_GT(double(near_core), 0.99 * double(cloud.size()));
  EXPECT_LT(worst_lfs_error, 0.1 * minor);
}

TEST(VoronoiPoles, ShiftedByAMillionMetresTheyShiftAlong) {
  const PointCloud cloud = test::thin_poisson(test::sample_torus(20000, 1.0, 0.4, 5), 0.08);
  const Vector3d shift(1.0e6, -2.0e6, 3.0e5);
  std::vector<Vector3d> moved = cloud.positions;
  for (Vector3d& x : moved) x += shift;
  const VoronoiPoles a = voronoi_poles(cloud.positions), b = voronoi_poles(moved);
  ASSERT_EQ(a.negative.size(), b.negative.size());
  EXPECT_EQ(a.hull_points, b.hull_points);
  double worst = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(a.negative[i].allFinite(), b.negative[i].allFinite()) << i;
    if (a.negative[i].allFinite()) worst = std::max(worst, (b.negative[i] - shift - a.negative[i]).norm());
    EXPECT_GT(a.axis[i].dot(b.axis[i]), 0.999999);
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(VoronoiPoles, RejectsTooFewNonFiniteAndFlatInput) {
  std::vector<Vector3d> three = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  EXPECT_THROW(voronoi_poles(three), UsageError);
  std::vector<Vector3d> flat;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) flat.emplace_back(i, j, 0.0);
  EXPECT_THROW(voronoi_poles(flat), ComputeError);
  std::vector<Vector3d> bad = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0, 0, NAN)};
  try {
    voronoi_poles(bad);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pointsurf
