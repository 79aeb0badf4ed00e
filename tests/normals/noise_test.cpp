// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/normals/noise.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

// A 60 x 60 grid of spacing 1 in the plane z = 0 (shifted far away), z displaced uniformly in
// [-amplitude, amplitude].
PointCloud noisy_plane(double amplitude, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PointCloud c;
  for (int j = 0; j < 60; ++j)
    for (int i = 0; i < 60; ++i) c.positions.emplace_back(2e6 + i, 3e6 + j, 50.0 + amplitude * u(rng));
  return c;
}

TEST(Noise, AnExactPlaneHasNoneAndUniformNoiseGivesItsRms) {
  const PointCloud exact = noisy_plane(0.0, 1);
  EXPECT_LT(estimate_noise(exact, KdTree(exact.positions)).median_in_spacings, 1e-6);
  for (const double a : {0.1, 0.2, 0.3}) {  // (at a = 1 the 3 nearest neighbours spread out in z too: 0.41 for 0.58)
    const PointCloud c = noisy_plane(a, 2);
    const NoiseEstimate e = estimate_noise(c, KdTree(c.positions));
    // RMS of uniform noise a / sqrt(3); the 3 nearest neighbours of a unit grid are about
    // 1 away (a little more with the noise), the fit takes up some of it: within 25 %.
    const double expected = a / std::sqrt(3.0);
    EXPECT_NEAR(e.median_in_spacings, expected, 0.25 * expected) << a;
    EXPECT_GE(e.p90_in_spacings, e.median_in_spacings);
    EXPECT_EQ(e.samples, 2000u);
  }
}

TEST(Noise, SeparatesACleanSphereFromANoisyOne) {
  PointCloud clean = test::sample_sphere(20000, 1.0, Vector3d::Zero(), 5);
  EXPECT_LT(estimate_noise(clean, KdTree(clean.positions)).median_in_spacings, 0.15);
  std::mt19937_64 rng(6);
  std::normal_distribution<double> g(0.0, 0.03);  // 1.7 mean spacings of 0.0177
  for (Vector3d& x : clean.positions) x *= 1.0 + g(rng);
  EXPECT_GT(estimate_noise(clean, KdTree(clean.positions)).median_in_spacings, kNoisyInSpacings);
}

TEST(Noise, RejectsTooFewNeighbours) {
  const PointCloud c = noisy_plane(0.1, 3);
  EXPECT_THROW(estimate_noise(c, KdTree(c.positions), 3), UsageError);
}

}  // namespace
}  // namespace pointsurf
