// SPDX-License-Identifier: GPL-3.0-or-later
// M3C2 on clouds whose separation is known: two parallel noisy planes (the distance along the
// normal, a level of detection that shrinks with the noise), a sphere against a larger one with
// outward normals (the sign follows cloud 1's normals), a 1e6 m shift, and the error paths.
#include "pointsurf/evaluate/m3c2.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

PointCloud noisy_plane(double z, double sigma, std::uint64_t seed, const Vector3d& shift = Vector3d::Zero()) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> xy(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma);
  PointCloud c;
  for (int i = 0; i < 4000; ++i) c.positions.push_back(shift + Vector3d(xy(rng), xy(rng), z + noise(rng)));
  return c;
}

M3c2Params scales(double normal, double projection, double depth) {
  M3c2Params p;
  p.normal_scale = normal;
  p.projection_scale = projection;
  p.max_depth = depth;
  return p;
}

TEST(M3c2, ParallelPlanesAreTheirSeparationApartWithALevelOfDetection) {
  const PointCloud a = noisy_plane(0.0, 0.005, 1), b = noisy_plane(0.2, 0.005, 2);
  const std::vector<Vector3d> core = {{0, 0, 0}, {0.3, -0.2, 0}, {-0.4, 0.5, 0}};
  M3c2Params p = scales(0.4, 0.2, 0.5);
  const M3c2Result r = m3c2_distances(a, b, core, p);
  ASSERT_EQ(r.valid, 3u);
  EXPECT_EQ(r.significant_count, 3u);
  for (std::size_t i = 0; i < core.size(); ++i) {
    EXPECT_NEAR(r.distance[i], 0.2, 0.004) << i;
    EXPECT_GT(r.lod95[i], 0.0);
    EXPECT_LT(r.lod95[i], 0.01);
    EXPECT_GT(r.normals[i].z(), 0.999);
    EXPECT_GT(r.count1[i], 20u);
  }
  // Noisier clouds: a wider level of detection.
  const M3c2Result noisy = m3c2_distances(noisy_plane(0.0, 0.05, 1), noisy_plane(0.2, 0.05, 2), core, p);
  EXPECT_GT(noisy.lod95[0], 3.0 * r.lod95[0]);
  // A registration error adds to it.
  p.registration_error = 0.5;
  const M3c2Result reg = m3c2_distances(a, b, core, p);
  EXPECT_NEAR(reg.lod95[0], r.lod95[0] + 0.5, 1e-12);
  EXPECT_EQ(reg.significant_count, 0u);
  // Invariant under a 1e6 m shift.
  const Vector3d shift(1e6, -2e6, 5e5);
  std::vector<Vector3d> moved;
  for (const Vector3d& c : core) moved.push_back(c + shift);
  p.registration_error = 0.0;
  const M3c2Result far = m3c2_distances(noisy_plane(0.0, 0.005, 1, shift), noisy_plane(0.2, 0.005, 2, shift), moved, p);
  for (std::size_t i = 0; i < core.size(); ++i) EXPECT_NEAR(far.distance[i], r.distance[i], 1e-9) << i;
}

TEST(M3c2, SignFollowsTheFirstCloudsNormals) {
  const PointCloud inner = test::sample_sphere(6000, 1.0, Vector3d::Zero(), 3), outer = test::sample_sphere(6000, 1.1, Vector3d::Zero(), 4);
  ASSERT_TRUE(inner.has_normals());
  const std::vector<Vector3d> core = {inner.positions[0], inner.positions[10], inner.positions[100]};
  const M3c2Params p = scales(0.3, 0.2, 0.3);
  const M3c2Result r = m3c2_distances(inner, outer, core, p);
  ASSERT_EQ(r.valid, 3u);
  for (std::size_t i = 0; i < core.size(); ++i) EXPECT_NEAR(r.distance[i], 0.1, 0.01) << i;
  const M3c2Result back = m3c2_distances(outer, inner, std::vector<Vector3d>{outer.positions[0]}, p);
  EXPECT_NEAR(back.distance[0], -0.1, 0.01);
}

TEST(M3c2, TooFewPointsGiveNoDistanceAndBadInputThrows) {
  const PointCloud a = noisy_plane(0.0, 0.001, 1), b = noisy_plane(0.2, 0.001, 2);
  M3c2Params p = scales(0.4, 0.2, 0.1);  // the cylinder does not reach cloud 2
  const M3c2Result r = m3c2_distances(a, b, std::vector<Vector3d>{{0, 0, 0}}, p);
  EXPECT_EQ(r.valid, 0u);
  EXPECT_TRUE(std::isnan(r.distance[0]));
  EXPECT_EQ(r.count2[0], 0u);
  EXPECT_THROW(m3c2_distances(PointCloud{}, b), InputError);
  p.min_points = 1;
  EXPECT_THROW(m3c2_distances(a, b, {}, p), UsageError);
  p.min_points = 3;
  p.max_depth = -1.0;
  EXPECT_THROW(m3c2_distances(a, b, {}, p), UsageError);
  // Derived scales are reported.
  const M3c2Result d = m3c2_distances(a, b, std::vector<Vector3d>{{0, 0, 0}});
  EXPECT_GT(d.normal_scale, 0.0);
  EXPECT_NEAR(d.projection_scale / d.normal_scale, 0.6, 1e-12);
}

}  // namespace
}  // namespace pointsurf
