// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/clean/remove_outliers.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "support/clean_shapes.h"
#include "support/features_shapes.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::expect_error;

// A sphere of radius 1 (20k points, spacing about 0.0063), Gaussian noise of 0.3 spacings,
// 150 drift points 5..25 spacings above it and 150 scattered through its bounding box.
struct Noisy {
  PointCloud cloud;
  std::vector<std::uint32_t> outliers;
  double spacing = 0.0;
};

Noisy noisy_sphere(std::size_t n = 20000) {
  Noisy s;
  s.cloud = test::sample_sphere(n, 1.0, Vector3d::Zero(), 3);
  s.spacing = mean_spacing(s.cloud.positions);
  test::add_noise(s.cloud, 0.3 * s.spacing, 4);
  s.outliers = test::add_drift_outliers(s.cloud, 150, 5.0 * s.spacing, 25.0 * s.spacing, 5);
  const std::vector<std::uint32_t> scattered =
      test::add_scattered_outliers(s.cloud, 150, 0.2, 10.0 * s.spacing, [](const Vector3d& p) { return test::distance_to_sphere(p); });
  s.outliers.insert(s.outliers.end(), scattered.begin(), scattered.end());
  return s;
}

std::vector<std::size_t> permutation(std::size_t n, std::uint64_t seed) {
  std::vector<std::size_t> perm(n);
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(seed));
  return perm;
}

// Kept indices of a permuted run, mapped back to the original indices and sorted.
std::vector<std::uint32_t> unpermute(const std::vector<std::uint32_t>& kept, const std::vector<std::size_t>& perm) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t i : kept) out.push_back(static_cast<std::uint32_t>(perm[i]));
  std::sort(out.begin(), out.end());
  return out;
}

TEST(StatisticalOutliers, MatchesTheDefinitionComputedByBruteForce) {
  Noisy s = noisy_sphere(3000);
  const StatisticalOutlierParams params{.k = 12, .std_ratio = 1.0};
  const OutlierResult result = remove_statistical_outliers(s.cloud, params);
  const std::size_t n = s.cloud.size();
  std::vector<double> mean(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<double> d;
    for (std::size_t j = 0; j < n; ++j) d.push_back((s.cloud.positions[j] - s.cloud.positions[i]).norm());
    std::partial_sort(d.begin(), d.begin() + params.k, d.end());
    mean[i] = std::accumulate(d.begin(), d.begin() + params.k, 0.0) / params.k;
  }
  const double mu = std::accumulate(mean.begin(), mean.end(), 0.0) / double(n);
  double squares = 0.0;
  for (double m : mean) squares += (m - mu) * (m - mu);
  const double threshold = mu + params.std_ratio * std::sqrt(squares / double(n - 1));
  EXPECT_NEAR(result.threshold, threshold, 1e-12 * threshold);
  std::vector<std::uint32_t> expected;
  for (std::size_t i = 0; i < n; ++i)
    if (mean[i] < threshold) expected.push_back(static_cast<std::uint32_t>(i));
  EXPECT_EQ(result.kept, expected);
  EXPECT_EQ(result.removed, n - expected.size());
}

TEST(StatisticalOutliers, FindsInjectedOutliersOnANoisySphere) {
  Noisy s = noisy_sphere();
  const OutlierResult result = remove_statistical_outliers(s.cloud);
  const test::Detection d = test::score_removal(result.kept, s.cloud.size(), s.outliers);
  std::printf("sor on a noisy sphere: precision %.3f recall %.3f\n", d.precision, d.recall);
  // Measured 0.85: scattered far outliers inflate the std the threshold is built from, so the
  // nearest ones pass (the method's known behaviour, same as Open3D's).
  EXPECT_GE(d.recall, 0.8);
  EXPECT_GE(d.precision, 0.9);
  EXPECT_EQ(result.kept.size() + result.removed, s.cloud.size());
  EXPECT_TRUE(std::is_sorted(result.kept.begin(), result.kept.end()));
}

TEST(StatisticalOutliers, SharesTheNormalsPassThroughMeanDistances) {
  // estimate_normals with keep_mean_distance computes the statistic in its own kNN pass: the
  // cut from those distances keeps exactly what remove_statistical_outliers keeps.
  Noisy s = noisy_sphere(8000);
  const KdTree tree(s.cloud.positions);
  const StatisticalOutlierParams sor;
  const OutlierResult direct = remove_statistical_outliers(s.cloud, sor, &tree);
  PointCloud work = s.cloud;
  NormalParams normals;
  normals.k = sor.k;
  normals.keep_mean_distance = true;
  estimate_normals(work, normals, &tree);
  const ScalarField* field = work.fields.find("mean_distance");
  ASSERT_NE(field, nullptr);
  EXPECT_EQ(field->type, ScalarType::Float64);
  const OutlierResult shared = statistical_outliers_from_distances(field->values, sor.std_ratio);
  EXPECT_EQ(shared.kept, direct.kept);
  EXPECT_DOUBLE_EQ(shared.threshold, direct.threshold);
  EXPECT_GT(direct.removed, 100u);
  expect_error<UsageError>([&] { statistical_outliers_from_distances(field->values, 0.0); }, "std_ratio");
  expect_error<UsageError>([&] { statistical_outliers_from_distances(std::vector<double>{1.0}, 2.0); }, "at least 2");
}

TEST(StatisticalOutliers, DropsStacksOfDuplicatesLikeOpen3D) {
  PointCloud cloud = test::sample_plane(500, 1.0, 2);
  for (int i = 0; i < 5; ++i) cloud.positions.push_back(Vector3d(0.5, 0.5, 0.0));
  const OutlierResult result = remove_statistical_outliers(cloud, {.k = 4, .std_ratio = 2.0});
  for (std::uint32_t i = 500; i < 505; ++i) EXPECT_FALSE(std::binary_search(result.kept.begin(), result.kept.end(), i)) << i;
}

// The kept set of `remove` must not change when the points are permuted or shifted by 1e6 m.
template <class Remove>
void expect_invariant_under_permutation_and_a_far_shift(Remove remove) {
  Noisy s = noisy_sphere(5000);
  const OutlierResult base = remove(s.cloud);
  const std::vector<std::size_t> perm = permutation(s.cloud.size(), 9);
  EXPECT_EQ(unpermute(remove(s.cloud.select(perm)).kept, perm), base.kept);
  PointCloud shifted = s.cloud;
  for (Vector3d& p : shifted.positions) p += Vector3d(1e6, -2e6, 1e6);
  EXPECT_EQ(remove(shifted).kept, base.kept);
}

TEST(StatisticalOutliers, InvariantUnderPermutationAndAFarShift) {
  expect_invariant_under_permutation_and_a_far_shift([](const PointCloud& c) { return remove_statistical_outliers(c); });
}

// A unit sphere whose density falls tenfold from the north pole to the south (a scan's near
// and far sides), with Gaussian noise of 0.2 local spacings: every point lies on the surface.
PointCloud uneven_sphere(std::uint64_t seed) {
  const PointCloud dense = test::sample_sphere(60000, 1.0, Vector3d::Zero(), seed);
  std::mt19937_64 rng(seed + 1);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<std::size_t> chosen;
  for (std::size_t i = 0; i < dense.size(); ++i)
    if (uniform(rng) < 0.1 + 0.9 * 0.5 * (dense.positions[i].z() + 1.0)) chosen.push_back(i);
  PointCloud cloud = dense.select(chosen);
  test::add_noise(cloud, 0.2 * mean_spacing(cloud.positions), seed + 2);
  return cloud;
}

TEST(LocalOutliers, KeepsEverySurfacePointWhereDensityVaries) {
  for (std::uint64_t seed : {21, 22}) {
    const PointCloud cloud = uneven_sphere(seed);
    const OutlierResult local = remove_local_outliers(cloud);
    const OutlierResult sor = remove_statistical_outliers(cloud);
    std::printf("uneven sphere (%zu points): local removes %zu (%.3f %%), sor %zu (%.3f %%)\n", cloud.size(), local.removed,
                100.0 * double(local.removed) / double(cloud.size()), sor.removed, 100.0 * double(sor.removed) / double(cloud.size()));
    EXPECT_LE(double(local.removed), 0.003 * double(cloud.size()));
    EXPECT_GT(sor.removed, 10 * std::max<std::size_t>(local.removed, 1));  // the global cut takes the sparse side
    EXPECT_EQ(local.kept.size() + local.removed, cloud.size());
    EXPECT_TRUE(std::is_sorted(local.kept.begin(), local.kept.end()));
  }
}

TEST(LocalOutliers, FindsFarOutliersInjectedAtKnownIndices) {
  // A noisy unit sphere (20k points, noise 0.3 spacing) with drift points 15..30 spacings above
  // it and points scattered through its bounding box at least 15 spacings from it: the
  // outliers' indices are known. 15 spacings is about min_ratio = 5 times the mean distance to
  // 16 neighbours on the surface (about 3 spacings).
  for (std::uint64_t seed : {31, 32}) {
    PointCloud cloud = test::sample_sphere(20000, 1.0, Vector3d::Zero(), seed);
    const double spacing = mean_spacing(cloud.positions);
    test::add_noise(cloud, 0.3 * spacing, seed + 1);
    std::vector<std::uint32_t> outliers = test::add_drift_outliers(cloud, 150, 15.0 * spacing, 30.0 * spacing, seed + 2);
    const std::vector<std::uint32_t> scattered = test::add_scattered_outliers(
        cloud, 150, 0.2, 15.0 * spacing, [](const Vector3d& p) { return test::distance_to_sphere(p); }, seed + 3);
    outliers.insert(outliers.end(), scattered.begin(), scattered.end());
    const OutlierResult result = remove_local_outliers(cloud);
    const test::Detection d = test::score_removal(result.kept, cloud.size(), outliers);
    std::printf("local on a noisy sphere with %zu far outliers: precision %.3f recall %.3f (ratio cut %.3g)\n", outliers.size(), d.precision,
                d.recall, result.threshold);
    EXPECT_GE(d.recall, 0.95);
    EXPECT_GE(d.precision, 0.95);
  }
}

// Issue 28's scan (bench/clean/outlier_sweep.sh) on analytic closed surfaces: samples with exact
// normals, Gaussian noise along the normal of 0.1 % of the diagonal, and 1 % outliers uniform in
// the bounding box grown by 0.1 on each side.
struct OutlierScan {
  PointCloud cloud;
  std::vector<std::uint32_t> outliers;
  double sigma = 0.0;
};
OutlierScan outlier_scan(PointCloud surface, const std::function<double(const Vector3d&)>& distance, std::uint64_t seed) {
  OutlierScan s;
  s.sigma = 0.001 * bounding_box(surface.positions).diagonal();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, s.sigma);
  for (std::size_t i = 0; i < surface.size(); ++i) surface.positions[i] += g(rng) * surface.normals[i];
  s.cloud = std::move(surface);
  s.outliers = test::add_scattered_outliers(s.cloud, s.cloud.size() / 100, 0.1, 0.0, distance, seed + 1);
  return s;
}

double distance_to_torus(const Vector3d& p) { return std::abs(std::hypot(std::hypot(p.x(), p.y()) - 1.0, p.z()) - 0.3); }

// Outliers farther than 5 sigma from the surface left, and surface samples removed.
struct ScanScore {
  std::size_t far = 0, far_left = 0, surface = 0, surface_removed = 0;
};
ScanScore score_scan(const OutlierScan& s, const OutlierResult& r, const std::function<double(const Vector3d&)>& distance) {
  ScanScore out;
  std::vector<bool> kept(s.cloud.size(), false), outlier(s.cloud.size(), false);
  for (std::uint32_t i : r.kept) kept[i] = true;
  for (std::uint32_t i : s.outliers) outlier[i] = true;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    if (outlier[i] && distance(s.cloud.positions[i]) > 5.0 * s.sigma) {
      ++out.far;
      out.far_left += kept[i];
    } else if (!outlier[i]) {
      ++out.surface;
      out.surface_removed += !kept[i];
    }
  }
  return out;
}

TEST(LocalOutliers, RemovesOutliersNearTheSurfaceAndKeepsCreases) {
  // Issue 28's target: at most 0.2 % of the outliers beyond 5 sigma left, at most 0.1 % of the
  // surface samples removed, here on a cube (12 creases, 8 corners) and a torus, 60k samples
  // and 600 outliers each, two seeds. The density test alone leaves the outliers that lie near
  // the surface at its density (about 5 % of them).
  struct Case {
    const char* name;
    std::function<PointCloud(std::uint64_t)> sample;
    std::function<double(const Vector3d&)> distance;
  };
  const Case cases[] = {
      {"cube", [](std::uint64_t seed) { return test::sample_cube_features(200000, 1.0, seed).cloud; },
       [](const Vector3d& p) { return test::distance_to_cube(p); }},
      {"torus", [](std::uint64_t seed) { return test::sample_torus(200000, 1.0, 0.3, seed); }, distance_to_torus},
  };
  for (const Case& c : cases) {
    ScanScore total, before;
    for (std::uint64_t seed : {41}) {
      const OutlierScan s = outlier_scan(c.sample(seed), c.distance, seed + 100);
      const ScanScore now = score_scan(s, remove_local_outliers(s.cloud), c.distance);
      const ScanScore density = score_scan(s, remove_local_outliers(s.cloud, {.surface_sigmas = 0.0}), c.distance);
      total.far += now.far, total.far_left += now.far_left, total.surface += now.surface, total.surface_removed += now.surface_removed;
      before.far_left += density.far_left, before.surface_removed += density.surface_removed;
    }
    std::printf("local on a %s with 1 %% outliers: %zu of %zu outliers beyond 5 sigma left (density test alone: %zu), %zu of %zu "
                "surface samples removed (%zu)\n", c.name, total.far_left, total.far, before.far_left, total.surface_removed, total.surface,
                before.surface_removed);
    EXPECT_LE(double(total.far_left), 0.002 * double(total.far)) << c.name;
    EXPECT_LE(double(total.surface_removed), 0.001 * double(total.surface)) << c.name;
    EXPECT_GE(before.far_left, 10 * std::max<std::size_t>(total.far_left, 1)) << c.name;
  }
}

TEST(LocalOutliers, KeepsAShellOfNoiseWiderThanTheNeighbourhoods) {
  // Noise wider than the neighbourhoods (sigma 3 spacings, as CGAL's sphere_20k.xyz): the planes
  // of 16 neighbours say nothing about the surface, and the surface test keeps the shell.
  PointCloud cloud = test::sample_sphere(20000, 1.0, Vector3d::Zero(), 51);
  test::add_noise(cloud, 3.0 * mean_spacing(cloud.positions), 52);
  const OutlierResult r = remove_local_outliers(cloud);
  std::printf("local on a sphere with noise of 3 spacings: %zu of %zu removed\n", r.removed, cloud.size());
  EXPECT_LE(double(r.removed), 0.001 * double(cloud.size()));
}

TEST(LocalOutliers, InvariantUnderPermutationAndAFarShift) {
  expect_invariant_under_permutation_and_a_far_shift([](const PointCloud& c) { return remove_local_outliers(c); });
}

TEST(RadiusOutliers, RemovesDriftPointsAndKeepsTheSurface) {
  Noisy s = noisy_sphere();
  const OutlierResult result = remove_radius_outliers(s.cloud);
  const test::Detection d = test::score_removal(result.kept, s.cloud.size(), s.outliers);
  std::printf("radius on a noisy sphere: precision %.3f recall %.3f\n", d.precision, d.recall);
  EXPECT_GE(d.recall, 0.95);
  EXPECT_GE(d.precision, 0.95);
  EXPECT_NEAR(result.threshold, 4.0 * mean_spacing(s.cloud.positions), 1e-12);
}

TEST(RadiusOutliers, CountsOtherPointsWithinTheRadiusInclusive) {
  PointCloud cloud;
  // A point with exactly 2 others at distance 1, and one with 1 other.
  cloud.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(-1, 0, 0), Vector3d(10, 0, 0), Vector3d(10, 1, 0)};
  const OutlierResult two = remove_radius_outliers(cloud, {.min_neighbours = 2, .radius = Length::cloud(1.0)});
  EXPECT_EQ(two.kept, (std::vector<std::uint32_t>{0}));
  const OutlierResult one = remove_radius_outliers(cloud, {.min_neighbours = 1, .radius = Length::cloud(1.0)});
  EXPECT_EQ(one.kept.size(), 5u);
  EXPECT_EQ(one.removed, 0u);
}

TEST(RadiusOutliers, InvariantUnderPermutationAndAFarShift) {
  Noisy s = noisy_sphere(5000);
  const RadiusOutlierParams params{.min_neighbours = 4, .radius = Length::cloud(4.0 * s.spacing)};
  const OutlierResult base = remove_radius_outliers(s.cloud, params);
  const std::vector<std::size_t> perm = permutation(s.cloud.size(), 10);
  EXPECT_EQ(unpermute(remove_radius_outliers(s.cloud.select(perm), params).kept, perm), base.kept);
  PointCloud shifted = s.cloud;
  for (Vector3d& p : shifted.positions) p += Vector3d(3e6, 1e6, -1e6);
  const OutlierResult far = remove_radius_outliers(shifted, params);
  // A neighbour exactly at the radius may fall either side after rounding at 1e6 m.
  EXPECT_LE(std::max(far.kept.size(), base.kept.size()) - std::min(far.kept.size(), base.kept.size()), 2u);
}

// The points judged outliers among the first `surface` points (all on the true surface), and
// those near the cube's edges and corners.
struct SurfaceLosses {
  std::size_t removed = 0, edge = 0, edge_removed = 0, corner = 0, corner_removed = 0;
};

SurfaceLosses surface_losses(const PointCloud& cloud, const OutlierResult& result, std::size_t surface, double spacing, bool cube) {
  std::vector<bool> kept(cloud.size(), false);
  for (std::uint32_t i : result.kept) kept[i] = true;
  SurfaceLosses l;
  for (std::size_t i = 0; i < surface; ++i) {
    l.removed += !kept[i];
    if (!cube) continue;
    const Vector3d& p = cloud.positions[i];
    if (test::distance_to_cube_edge(p) <= 2.0 * spacing) ++l.edge, l.edge_removed += !kept[i];
    if ((p.cwiseAbs() - Vector3d::Constant(1.0)).norm() <= 3.0 * spacing) ++l.corner, l.corner_removed += !kept[i];
  }
  return l;
}

TEST(RansacOutliers, RemovesPointsOffTheFacesOfANoisyCubeAndKeepsEdgesAndCorners) {
  PointCloud cloud = test::sample_cube(20000, 1.0, 6);
  const double spacing = mean_spacing(cloud.positions);
  test::add_noise(cloud, 0.2 * spacing, 8);
  const std::size_t surface = cloud.size();
  const std::vector<std::uint32_t> outliers = test::add_drift_outliers(cloud, 200, 3.0 * spacing, 15.0 * spacing, 12);
  const OutlierResult result = remove_ransac_outliers(cloud);
  const test::Detection d = test::score_removal(result.kept, cloud.size(), outliers);
  const SurfaceLosses l = surface_losses(cloud, result, surface, spacing, true);
  std::printf("ransac on a noisy cube: precision %.3f recall %.3f; edge points removed %zu/%zu, corner %zu/%zu\n", d.precision,
              d.recall, l.edge_removed, l.edge, l.corner_removed, l.corner);
  // Measured: precision 1.000, recall 1.000 (before the refit and dominance tests: 1.000 / 0.625).
  EXPECT_GE(d.recall, 0.98);
  EXPECT_GE(d.precision, 0.98);
  // Points near the edges and corners fit the plane of their own face. Measured: 0 of 1379
  // within 2 spacings of an edge, 0 of 52 within 3 spacings of a corner.
  ASSERT_GT(l.edge, 500u);
  ASSERT_GT(l.corner, 20u);
  EXPECT_LE(double(l.edge_removed), 0.01 * double(l.edge));
  EXPECT_LE(l.corner_removed, 1u);
}

TEST(RansacOutliers, HeavierNoiseOnACubeAndASphere) {
  // Noise 0.5 spacing: surface points stray a spacing from their plane; the acceptance band
  // grows with the inliers' RMS residual (4 of them, at most 2 distances).
  {
    PointCloud cloud = test::sample_cube(20000, 1.0, 6);
    const double spacing = mean_spacing(cloud.positions);
    test::add_noise(cloud, 0.5 * spacing, 8);
    const std::size_t surface = cloud.size();
    const std::vector<std::uint32_t> outliers = test::add_drift_outliers(cloud, 200, 3.0 * spacing, 15.0 * spacing, 12);
    const OutlierResult result = remove_ransac_outliers(cloud);
    const test::Detection d = test::score_removal(result.kept, cloud.size(), outliers);
    const SurfaceLosses l = surface_losses(cloud, result, surface, spacing, true);
    std::printf("ransac, cube, noise 0.5: precision %.3f recall %.3f; surface points removed %zu, near edges %zu/%zu\n", d.precision,
                d.recall, l.removed, l.edge_removed, l.edge);
    // Measured: precision 0.985, recall 0.990, 3 of 20000 surface points removed, 0 of 1354
    // near edges (local planes only: 0.980 / 0.980, 4 removed, 1 of 1354)
    // near the edges (before: 1.000 / 0.325).
    EXPECT_GE(d.precision, 0.95);
    EXPECT_GE(d.recall, 0.95);
    EXPECT_LE(double(l.edge_removed), 0.01 * double(l.edge));
  }
  {
    PointCloud cloud = test::sample_sphere(20000, 1.0, Vector3d::Zero(), 3);
    const double spacing = mean_spacing(cloud.positions);
    test::add_noise(cloud, 0.5 * spacing, 4);
    const std::vector<std::uint32_t> outliers = test::add_drift_outliers(cloud, 200, 3.0 * spacing, 15.0 * spacing, 5);
    const OutlierResult result = remove_ransac_outliers(cloud);
    const test::Detection d = test::score_removal(result.kept, cloud.size(), outliers);
    std::printf("ransac, sphere, noise 0.5: precision %.3f recall %.3f\n", d.precision, d.recall);
    // Measured: precision 0.980, recall 1.000 (local planes only: 0.975 / 0.995; before the
    // refit: 1.000 / 0.360).
    EXPECT_GE(d.precision, 0.95);
    EXPECT_GE(d.recall, 0.95);
  }
}

TEST(RansacOutliers, KeepsCurvedSurfacesAndFindsDriftAndScatteredPoints) {
  // Small spheres: 24 neighbours span 0.25 (2000 points) to 0.35 (1000) radians of arc, so the
  // local planes are visibly curved.
  for (std::size_t n : {1000, 2000}) {
    PointCloud cloud = test::sample_sphere(n, 1.0, Vector3d::Zero(), 7);
    const double spacing = mean_spacing(cloud.positions);
    test::add_noise(cloud, 0.2 * spacing, 8);
    const std::vector<std::uint32_t> outliers = test::add_drift_outliers(cloud, n / 100, 3.0 * spacing, 10.0 * spacing, 9);
    const OutlierResult result = remove_ransac_outliers(cloud);
    const test::Detection d = test::score_removal(result.kept, cloud.size(), outliers);
    std::printf("ransac, sphere of %zu points: precision %.3f recall %.3f\n", n, d.precision, d.recall);
    // Measured: precision 1.000, recall 1.000 for both (before: recall 0.500 and 0.600).
    EXPECT_EQ(surface_losses(cloud, result, n, spacing, false).removed, 0u) << n;
    EXPECT_GE(d.recall, 0.95) << n;
  }
  // Drift and scattered points together (the sphere of the other filters' tests).
  Noisy s = noisy_sphere();
  const OutlierResult result = remove_ransac_outliers(s.cloud);
  const test::Detection d = test::score_removal(result.kept, s.cloud.size(), s.outliers);
  std::printf("ransac on a noisy sphere: precision %.3f recall %.3f\n", d.precision, d.recall);
  // Measured: precision 1.000, recall 1.000 (before: 1.000 / 0.570).
  EXPECT_GE(d.precision, 0.98);
  EXPECT_GE(d.recall, 0.98);
}

TEST(RansacOutliers, RemovesSmallClustersOfDriftPoints) {
  // Drift points in clusters of `size` (a seeded drift point and size - 1 copies jittered by
  // a spacing around it): each point's neighbourhood holds size - 1 other drift points, which
  // form no plane as well supported as the surface below them.
  for (std::size_t size : {2, 4, 6}) {
    PointCloud cloud = test::sample_sphere(20000, 1.0, Vector3d::Zero(), 3);
    const double spacing = mean_spacing(cloud.positions);
    test::add_noise(cloud, 0.2 * spacing, 4);
    std::vector<std::uint32_t> outliers = test::add_drift_outliers(cloud, 40, 3.0 * spacing, 10.0 * spacing, 5);
    std::mt19937_64 rng(size);
    std::normal_distribution<double> jitter(0.0, spacing);
    PointCloud extra;
    for (std::uint32_t o : std::vector<std::uint32_t>(outliers))
      for (std::size_t j = 1; j < size; ++j) {
        const double x = jitter(rng), y = jitter(rng), z = jitter(rng);
        outliers.push_back(static_cast<std::uint32_t>(cloud.size() + extra.size()));
        extra.positions.push_back(cloud.positions[o] + Vector3d(x, y, z));
        extra.normals.push_back(cloud.normals[o]);
      }
    cloud.append(extra);
    const OutlierResult result = remove_ransac_outliers(cloud);
    const test::Detection d = test::score_removal(result.kept, cloud.size(), outliers);
    std::printf("ransac, drift clusters of %zu: precision %.3f recall %.3f\n", size, d.precision, d.recall);
    // Measured: precision 1.000 for all; recall 0.988, 1.000, 0.983 for clusters of 2, 4, 6
    // (local planes only: 0.988, 0.981, 0.908: a plane through the point must hold 4 of its 23 neighbours off the dominant plane;
    // with the dominance test alone: 0.988, 0.825, 0.296).
    EXPECT_GE(d.precision, 0.98) << size;
    EXPECT_GE(d.recall, size < 6 ? 0.95 : 0.85) << size;
  }
}

// A plane, a sphere and a cylinder sampled at about one point per `area` with exact normals.
PointCloud primitive_scene(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud c;
  const double density = 500.0;  // points per unit area
  for (int i = 0; i < int(16.0 * density); ++i) {
    c.positions.emplace_back(4.0 * u(rng) - 2.0, 4.0 * u(rng) - 2.0, 0.0);
    c.normals.push_back(Vector3d::UnitZ());
  }
  const Vector3d centre(-1.0, -1.0, 1.0);
  for (int i = 0; i < int(4.0 * M_PI * 0.09 * density); ++i) {
    const double z = 2.0 * u(rng) - 1.0, phi = 2.0 * M_PI * u(rng), r = std::sqrt(1.0 - z * z);
    const Vector3d n(r * std::cos(phi), r * std::sin(phi), z);
    c.positions.push_back(centre + 0.3 * n);
    c.normals.push_back(n);
  }
  for (int i = 0; i < int(2.0 * M_PI * 0.15 * 1.5 * density); ++i) {
    const double phi = 2.0 * M_PI * u(rng);
    const Vector3d n(std::cos(phi), std::sin(phi), 0.0);
    c.positions.push_back(Vector3d(1.0, 1.0, 0.5 + 1.5 * u(rng)) + 0.15 * n);
    c.normals.push_back(n);
  }
  return c;
}

// A bumpy height field over [-1, 1]^2 with exact normals.
PointCloud bumpy_field(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng);
    c.positions.emplace_back(x, y, 0.15 * std::sin(3.0 * x) * std::cos(4.0 * y) + 0.1 * x * y);
    c.normals.push_back(Vector3d(-(0.45 * std::cos(3.0 * x) * std::cos(4.0 * y) + 0.1 * y),
                                 -(-0.6 * std::sin(3.0 * x) * std::sin(4.0 * y) + 0.1 * x), 1.0)
                            .normalized());
  }
  return c;
}

TEST(RansacOutliers, PrimitivesDoNoWorseThanLocalPlanesOnAPrimitiveSceneAndAFreeFormSurface) {
  PointCloud scene = primitive_scene(5);
  const std::size_t surface = scene.size();
  const double spacing = mean_spacing(scene.positions);
  test::add_noise(scene, 0.4 * spacing, 6);
  const std::vector<std::uint32_t> outliers = test::add_drift_outliers(scene, surface / 50, 3.0 * spacing, 10.0 * spacing, 7);
  RansacOutlierParams planes_only;
  planes_only.primitives = false;
  const test::Detection before = test::score_removal(remove_ransac_outliers(scene, planes_only).kept, scene.size(), outliers);
  const test::Detection after = test::score_removal(remove_ransac_outliers(scene).kept, scene.size(), outliers);
  std::printf("ransac, plane + sphere + cylinder, 2%% drift: local planes precision %.3f recall %.3f; primitives precision %.3f recall %.3f\n",
              before.precision, before.recall, after.precision, after.recall);
  // Measured: local planes precision 1.000 recall 0.984; primitives 1.000 / 1.000.
  EXPECT_GE(after.precision, before.precision);
  EXPECT_GE(after.recall, before.recall);
  EXPECT_GE(after.recall, 0.95);

  PointCloud field = bumpy_field(8000, 9);
  const double field_spacing = mean_spacing(field.positions);
  test::add_noise(field, 0.2 * field_spacing, 10);
  const std::vector<std::uint32_t> field_outliers = test::add_drift_outliers(field, 160, 3.0 * field_spacing, 10.0 * field_spacing, 11);
  const OutlierResult field_before = remove_ransac_outliers(field, planes_only);
  const OutlierResult field_after = remove_ransac_outliers(field);
  const std::size_t lost_before = surface_losses(field, field_before, 8000, field_spacing, false).removed;
  const std::size_t lost_after = surface_losses(field, field_after, 8000, field_spacing, false).removed;
  const test::Detection fb = test::score_removal(field_before.kept, field.size(), field_outliers);
  const test::Detection fa = test::score_removal(field_after.kept, field.size(), field_outliers);
  std::printf("ransac, bumpy height field: inliers removed %zu (local planes) vs %zu (primitives); recall %.3f vs %.3f\n", lost_before,
              lost_after, fb.recall, fa.recall);
  // Measured: 0 inliers removed by either, recall 1.000 for both (a quarter of the neighbours
  // instead of 3/4 as the primitive's share lost 1).
  EXPECT_LE(lost_after, lost_before);
}

TEST(RansacOutliers, InvariantUnderPermutation) {
  PointCloud cloud = test::sample_sphere(4000, 1.0, Vector3d::Zero(), 2);
  const double spacing = mean_spacing(cloud.positions);
  test::add_noise(cloud, 0.3 * spacing, 2);
  test::add_drift_outliers(cloud, 40, 2.0 * spacing, 8.0 * spacing, 3);
  const OutlierResult base = remove_ransac_outliers(cloud);
  const std::vector<std::size_t> perm = permutation(cloud.size(), 11);
  EXPECT_EQ(unpermute(remove_ransac_outliers(cloud.select(perm)).kept, perm), base.kept);
  // Measured: the 40 drift points and nothing else (before: 27 of them).
  EXPECT_GE(base.removed, 38u);
  EXPECT_LE(base.removed, 42u);
}

TEST(KeepPoints, KeepsAttributesAndChecksIndices) {
  PointCloud cloud = test::sample_sphere(10);
  cloud.colors.assign(10, Vector3f(0.5f, 0.25f, 1.0f));
  ScalarField& f = cloud.fields.add("intensity", 10, ScalarType::UInt16);
  std::iota(f.values.begin(), f.values.end(), 0.0);
  const PointCloud kept = keep_points(cloud, std::vector<std::uint32_t>{2, 7});
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(kept.positions[1], cloud.positions[7]);
  EXPECT_EQ(kept.normals[0], cloud.normals[2]);
  EXPECT_EQ(kept.fields.find("intensity")->values, (std::vector<double>{2.0, 7.0}));
  EXPECT_EQ(kept.fields.find("intensity")->type, ScalarType::UInt16);
  expect_error<UsageError>([&] { keep_points(cloud, std::vector<std::uint32_t>{10}); }, "keep_points: index 10 out of range for 10 points");
}

TEST(Outliers, BadParametersAreUsageErrors) {
  const PointCloud cloud = test::sample_sphere(100);
  expect_error<UsageError>([&] { remove_statistical_outliers(cloud, {.k = 0}); }, "remove_statistical_outliers: k must be >= 1, got 0");
  expect_error<UsageError>([&] { remove_statistical_outliers(cloud, {.k = 5, .std_ratio = 0.0}); }, "std_ratio must be > 0, got 0");
  expect_error<UsageError>([&] { remove_statistical_outliers(cloud, {.k = 5, .std_ratio = NAN}); }, "std_ratio must be > 0");
  expect_error<UsageError>([&] { remove_radius_outliers(cloud, {.min_neighbours = 0}); }, "min_neighbors must be >= 1, got 0");
  expect_error<UsageError>([&] { remove_radius_outliers(cloud, {.radius = Length::cloud(-1.0)}); }, "remove_radius_outliers: radius must be > 0, got -1");
  expect_error<UsageError>([&] { remove_radius_outliers(cloud, {.radius = Length::spacings(0.0)}); }, "radius must be > 0, got 0sp");
  expect_error<UsageError>([&] { remove_ransac_outliers(cloud, {.k = 3}); }, "remove_ransac_outliers: k must be >= 4, got 3");
  expect_error<UsageError>([&] { remove_ransac_outliers(cloud, {.iterations = 0}); }, "iterations must be >= 1, got 0");
  expect_error<UsageError>([&] { remove_ransac_outliers(cloud, {.distance = Length::cloud(-0.5)}); }, "distance must be > 0, got -0.5");
  expect_error<UsageError>([&] { remove_ransac_outliers(cloud, {.min_support = 0.0}); }, "min_support must be in (0, 1], got 0");
  expect_error<UsageError>([&] { remove_ransac_outliers(cloud, {.min_support = 1.5}); }, "min_support must be in (0, 1], got 1.5");
  expect_error<UsageError>([&] { remove_ransac_outliers(cloud, {.min_relative_support = -0.1}); },
                           "min_relative_support must be in [0, 1], got -0.1");
  expect_error<UsageError>([&] { remove_ransac_outliers(cloud, {.min_relative_support = NAN}); }, "min_relative_support must be in [0, 1]");
  expect_error<UsageError>([&] { remove_local_outliers(cloud, {.k = 1}); }, "remove_local_outliers: k must be >= 2, got 1");
  expect_error<UsageError>([&] { remove_local_outliers(cloud, {.min_ratio = 1.0}); }, "min_ratio must be > 1, got 1");
  expect_error<UsageError>([&] { remove_local_outliers(cloud, {.mad_sigmas = 0.0}); }, "mad_sigmas must be > 0, got 0");
  expect_error<UsageError>([&] { remove_local_outliers(cloud, {.far_ratio = 0.5}); }, "far_ratio must be > 1, got 0.5");
  expect_error<UsageError>([&] { remove_local_outliers(cloud, {.surface_sigmas = -1.0}); }, "surface_sigmas must be >= 0, got -1");
  expect_error<UsageError>([&] { remove_local_outliers(cloud, {.surface_floor = 0.0}); }, "surface_floor must be > 0, got 0");
  expect_error<UsageError>([&] { remove_local_outliers(test::sample_sphere(16)); }, "needs at least 17 points, got 16");
  PointCloud one;
  one.positions = {Vector3d::Zero()};
  expect_error<UsageError>([&] { remove_statistical_outliers(one); }, "needs at least 2 points, got 1");
  expect_error<UsageError>([&] { remove_ransac_outliers(PointCloud{}); }, "needs at least 4 points, got 0");
  const KdTree other(test::sample_sphere(50).positions);
  expect_error<UsageError>([&] { remove_radius_outliers(cloud, {}, &other); }, "the kd-tree holds 50 points but the cloud has 100");
}

TEST(Outliers, ReuseATreeAndCancel) {
  Noisy s = noisy_sphere(5000);
  const KdTree tree(s.cloud.positions);
  EXPECT_EQ(remove_statistical_outliers(s.cloud, {}, &tree).kept, remove_statistical_outliers(s.cloud).kept);
  const ProgressCallback stop = [](double) { return false; };
  EXPECT_THROW(remove_statistical_outliers(s.cloud, {}, &tree, stop), CancelledError);
  EXPECT_THROW(remove_radius_outliers(s.cloud, {}, &tree, stop), CancelledError);
  EXPECT_THROW(remove_ransac_outliers(s.cloud, {}, &tree, stop), CancelledError);
  double last = -1.0;
  bool monotone = true;
  remove_statistical_outliers(s.cloud, {}, &tree, [&](double f) {
    monotone = monotone && f >= last && f <= 1.0;
    last = f;
    return true;
  });
  EXPECT_TRUE(monotone);
  EXPECT_EQ(last, 1.0);
}


// Each removal method's table: the count, then the threshold under the key that says what it
// is, each in its block.
TEST(OutlierResult, EachMethodReportsItsThresholdUnderItsOwnKey) {
  OutlierResult r;
  r.removed = 5;
  r.threshold = 0.125;
  const std::vector<std::pair<std::string, std::string>> keys = {
      {"local", "ratio_threshold"}, {"sor", "mean_distance_threshold"}, {"radius", "radius_used"}, {"ransac", "distance_used"}};
  for (const auto& [method, key] : keys) {
    std::vector<std::pair<ResultBlock, std::string>> blocks;
    ResultList values;
    OutlierResult::results(method).record_blocks(r, [&](ResultBlock b, std::string k, ResultValue v) {
      blocks.emplace_back(b, k);
      values.emplace_back(std::move(k), std::move(v));
    }, method + ".");
    EXPECT_EQ(blocks, (std::vector<std::pair<ResultBlock, std::string>>{{ResultBlock::Counts, method + ".removed"},
                                                                         {ResultBlock::Metrics, method + "." + key}}));
    EXPECT_EQ(values, (ResultList{{method + ".removed", std::int64_t{5}}, {method + "." + key, 0.125}}));
    EXPECT_EQ(OutlierResult::results(method).specs()[1].unit, method == "local" ? "" : "cloud units");
  }
  EXPECT_THROW(OutlierResult::results("duplicates"), std::logic_error);
}

}  // namespace
}  // namespace pointsurf
