// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/clean/smooth_points.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "support/clean_shapes.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::expect_error;

// A shape sampled, noised by `noise_in_spacings` and given PCA normals (k 30), as a scan would
// arrive: the normals near creases are blended.
struct NoisyScan {
  PointCloud cloud;
  double spacing = 0.0;
};

NoisyScan noisy(PointCloud cloud, double noise_in_spacings, std::uint64_t seed) {
  NoisyScan s;
  s.spacing = mean_spacing(cloud.positions);
  test::add_noise(cloud, noise_in_spacings * s.spacing, seed);
  cloud.normals.clear();
  estimate_normals(cloud, {.keep_variation = false});
  s.cloud = std::move(cloud);
  return s;
}

auto sphere_distance = [](const Vector3d& p) { return test::distance_to_sphere(p); };
auto cube_distance = [](const Vector3d& p) { return test::distance_to_cube(p); };

TEST(Bilateral, ReducesNoiseOnASphere) {
  NoisyScan s = noisy(test::sample_sphere(20000, 1.0, Vector3d::Zero(), 5), 0.4, 6);
  const double before = test::rms_distance(s.cloud.positions, sphere_distance);
  PointCloud cloud = s.cloud;
  const SmoothResult r = smooth_bilateral(cloud);
  const double after = test::rms_distance(cloud.positions, sphere_distance);
  EXPECT_LT(after, 0.5 * before) << before << " -> " << after;
  EXPECT_GE(r.moved, cloud.size() - 10);
  EXPECT_GT(r.rms_displacement, 0.5 * before);
  EXPECT_LE(r.mean_displacement, r.rms_displacement);
  EXPECT_LE(r.rms_displacement, r.max_displacement);
  EXPECT_NEAR(r.radius_used, 3.0 * mean_spacing(s.cloud.positions), 1e-12);
  EXPECT_EQ(cloud.normals, s.cloud.normals);  // bilateral keeps the normals
}

// The cube's 90-degree edges: RMS distance to the true cube of the points within 2 spacings of
// an edge, and of the flat points farther than 5 spacings from every edge.
struct CubeFigures {
  double edge = 0.0, flat = 0.0;
};

CubeFigures cube_figures(const std::vector<Vector3d>& points, const std::vector<Vector3d>& reference, double spacing) {
  std::vector<bool> edge(points.size()), flat(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double e = test::distance_to_cube_edge(reference[i]);
    edge[i] = e <= 2.0 * spacing;
    flat[i] = e > 5.0 * spacing;
  }
  return {test::rms_distance(points, cube_distance, edge), test::rms_distance(points, cube_distance, flat)};
}

TEST(Trilateral, KeepsCubeEdgesSharperThanBilateralAtTheSameNoiseReduction) {
  NoisyScan s = noisy(test::sample_cube(30000, 1.0, 7), 0.4, 8);
  const CubeFigures before = cube_figures(s.cloud.positions, s.cloud.positions, s.spacing);
  PointCloud bilateral = s.cloud, trilateral = s.cloud;
  smooth_bilateral(bilateral);
  const SmoothResult tri = smooth_trilateral(trilateral);
  const CubeFigures b = cube_figures(bilateral.positions, s.cloud.positions, s.spacing);
  const CubeFigures t = cube_figures(trilateral.positions, s.cloud.positions, s.spacing);
  std::printf("cube: before edge %.5f flat %.5f | bilateral edge %.5f flat %.5f | trilateral edge %.5f flat %.5f\n", before.edge,
              before.flat, b.edge, b.flat, t.edge, t.flat);
  // Both denoise the flat faces by at least half, within 25% of each other.
  EXPECT_LT(b.flat, 0.5 * before.flat);
  EXPECT_LT(t.flat, 0.5 * before.flat);
  EXPECT_LT(std::max(b.flat, t.flat), 1.25 * std::min(b.flat, t.flat));
  // Near the edges the trilateral result stays measurably closer to the true cube.
  EXPECT_LT(t.edge, 0.93 * b.edge);  // measured 0.87x (plain bilateral is 1x)
  EXPECT_LT(t.edge, before.edge);
  EXPECT_GT(tri.normals_changed, 0u);
  for (const Vector3d& n : trilateral.normals) EXPECT_NEAR(n.norm(), 1.0, 1e-9);
}

TEST(Trilateral, FiltersNormalsWithinFacesNotAcrossEdges) {
  NoisyScan s = noisy(test::sample_cube(30000, 1.0, 9), 0.3, 10);
  PointCloud cloud = s.cloud;
  smooth_trilateral(cloud);
  // The true normal of a point is that of its nearest face.
  auto face_normal = [](const Vector3d& p) {
    Vector3d n = Vector3d::Zero();
    int axis = 0;
    p.cwiseAbs().maxCoeff(&axis);
    n[axis] = p[axis] > 0 ? 1.0 : -1.0;
    return n;
  };
  auto error = [&](const Vector3d& truth, const Vector3d& n) { return std::acos(std::min(1.0, std::abs(truth.dot(n)))); };
  double edge_before = 0.0, edge_after = 0.0, flat_before = 0.0, flat_after = 0.0;
  std::size_t edge = 0, flat = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double e = test::distance_to_cube_edge(s.cloud.positions[i]);
    const Vector3d truth = face_normal(s.cloud.positions[i]);
    if (e <= 1.5 * s.spacing) {
      edge_before += error(truth, s.cloud.normals[i]), edge_after += error(truth, cloud.normals[i]), ++edge;
    } else if (e > 6.0 * s.spacing) {
      flat_before += error(truth, s.cloud.normals[i]), flat_after += error(truth, cloud.normals[i]), ++flat;
    }
  }
  ASSERT_GT(edge, 300u);
  ASSERT_GT(flat, 3000u);
  std::printf("trilateral normal error: flat %.4f -> %.4f rad, near edges %.3f -> %.3f rad\n", flat_before / double(flat),
              flat_after / double(flat), edge_before / double(edge), edge_after / double(edge));
  // Within a face the noise in the normals drops; near an edge the filter does not blend the
  // two faces further (a plain average of neighbour normals would).
  EXPECT_LT(flat_after, 0.85 * flat_before);  // measured 0.75x
  EXPECT_LT(edge_after, 1.1 * edge_before);    // measured 1.05x
}

TEST(Trilateral, UsesAFeatureFieldWhenPresent) {
  NoisyScan s = noisy(test::sample_cube(20000, 1.0, 11), 0.4, 12);
  PointCloud flagged = s.cloud;
  ScalarField& feature = flagged.fields.add("feature", flagged.size(), ScalarType::UInt8);
  for (std::size_t i = 0; i < flagged.size(); ++i) feature.values[i] = test::distance_to_cube_edge(flagged.positions[i]) < s.spacing;
  PointCloud plain = s.cloud;
  smooth_trilateral(flagged);
  smooth_trilateral(plain);
  const CubeFigures f = cube_figures(flagged.positions, s.cloud.positions, s.spacing);
  const CubeFigures p = cube_figures(plain.positions, s.cloud.positions, s.spacing);
  EXPECT_LE(f.edge, 1.1 * p.edge);
  EXPECT_NE(flagged.positions, plain.positions);
  PointCloud ignored = s.cloud;
  ignored.fields = flagged.fields;
  smooth_trilateral(ignored, {.use_feature_field = false});
  EXPECT_EQ(ignored.positions, plain.positions);
}

TEST(Smoothing, InvariantUnderPermutationRigidMotionAndAFarShift) {
  NoisyScan s = noisy(test::sample_cube(6000, 1.0, 13), 0.4, 14);
  PointCloud base = s.cloud;
  smooth_trilateral(base);
  std::vector<std::size_t> perm(s.cloud.size());
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(4));
  PointCloud permuted = s.cloud.select(perm);
  smooth_trilateral(permuted);
  for (std::size_t i = 0; i < perm.size(); ++i) EXPECT_LT((permuted.positions[i] - base.positions[perm[i]]).norm(), 1e-9);
  const Vector3d offset(1e6, 2e6, -3e6);
  PointCloud shifted = s.cloud;
  for (Vector3d& p : shifted.positions) p += offset;
  smooth_trilateral(shifted);
  PointCloud shifted_b = s.cloud;
  for (Vector3d& p : shifted_b.positions) p += offset;
  PointCloud base_b = s.cloud;
  smooth_bilateral(shifted_b);
  smooth_bilateral(base_b);
  double worst = 0.0;
  for (std::size_t i = 0; i < base.size(); ++i) {
    worst = std::max(worst, (shifted.positions[i] - offset - base.positions[i]).norm());
    worst = std::max(worst, (shifted_b.positions[i] - offset - base_b.positions[i]).norm());
  }
  EXPECT_LT(worst, 1e-6 * s.spacing);
  const Eigen::AngleAxisd rotation(0.6, Vector3d(1, 2, 3).normalized());
  PointCloud rotated = s.cloud;
  for (Vector3d& p : rotated.positions) p = rotation * p;
  for (Vector3d& n : rotated.normals) n = rotation * n;
  smooth_trilateral(rotated);
  worst = 0.0;
  for (std::size_t i = 0; i < base.size(); ++i) worst = std::max(worst, (rotation.inverse() * rotated.positions[i] - base.positions[i]).norm());
  EXPECT_LT(worst, 1e-6 * s.spacing);
}

TEST(Smoothing, BadParametersAreUsageErrors) {
  PointCloud cloud = test::sample_sphere(200);
  expect_error<UsageError>([&] { smooth_bilateral(cloud, {.radius = Length::cloud(-1.0)}); }, "smooth_bilateral: radius must be > 0, got -1");
  expect_error<UsageError>([&] { smooth_bilateral(cloud, {.radius = Length::spacings(0.0)}); }, "radius must be > 0, got 0sp");
  expect_error<UsageError>([&] { smooth_bilateral(cloud, {.max_neighbours = 2}); }, "max_neighbors must be >= 3, got 2");
  expect_error<UsageError>([&] { smooth_bilateral(cloud, {.height_sigma = Length::cloud(-2.0)}); }, "height_sigma must be > 0, got -2");
  expect_error<UsageError>([&] { smooth_bilateral(cloud, {.iterations = 0}); }, "iterations must be >= 1, got 0");
  expect_error<UsageError>([&] { smooth_trilateral(cloud, {.sharpness_angle_deg = 0.0}); },
                           "smooth_trilateral: sharpness_angle_deg must be in (0, 90] degrees, got 0");
  expect_error<UsageError>([&] { smooth_trilateral(cloud, {.sharpness_angle_deg = 120.0}); }, "got 120");
  expect_error<UsageError>([&] { smooth_trilateral(cloud, {.normal_iterations = 0}); }, "normal_iterations must be >= 1, got 0");
  PointCloud bare = cloud;
  bare.normals.clear();
  expect_error<UsageError>([&] { smooth_bilateral(bare); }, "smooth_bilateral: the cloud has no normals; estimate and orient them first");
  expect_error<UsageError>([&] { smooth_trilateral(bare); }, "smooth_trilateral: the cloud has no normals");
  bare.normals.resize(5);
  expect_error<UsageError>([&] { smooth_bilateral(bare); }, "the cloud has 5 normals for 200 points");
}

TEST(Smoothing, CancelLeavesTheCloudUnchanged) {
  PointCloud cloud = test::sample_sphere(3000);
  test::add_noise(cloud, 0.01, 3);
  const PointCloud original = cloud;
  EXPECT_THROW(smooth_bilateral(cloud, {}, nullptr, [](double) { return false; }), CancelledError);
  EXPECT_THROW(smooth_trilateral(cloud, {}, nullptr, [](double f) { return f < 0.3; }), CancelledError);
  EXPECT_EQ(cloud.positions, original.positions);
  EXPECT_EQ(cloud.normals, original.normals);
}

}  // namespace
}  // namespace pointsurf
