// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/features/feature_points.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/features_shapes.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

// Scoring bands, in mean spacings of the noiseless cloud: a point within kTruth of a sharp edge
// must be labelled; a labelled point within kTolerance is correct.
constexpr double kTruth = 1.0;
constexpr double kTolerance = 1.5;

const std::vector<double>& labels_of(const PointCloud& cloud) {
  const ScalarField* field = cloud.fields.find("feature");
  EXPECT_NE(field, nullptr);
  static const std::vector<double> none;
  return field == nullptr ? none : field->values;
}

test::FeatureScore detect_and_score(test::FeatureShape shape, double noise_in_spacings, const FeatureParams& params = {}) {
  const double spacing = mean_spacing(shape.cloud.positions);
  test::add_feature_noise(shape, noise_in_spacings * spacing);
  shape.cloud.normals.clear();
  detect_feature_points(shape.cloud, params);
  return test::score_features(labels_of(shape.cloud), shape.edge_distance, kTruth * spacing, kTolerance * spacing);
}

// Share of points whose labels differ.
double label_disagreement(const std::vector<double>& a, const std::vector<double>& b) {
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
  return double(differ) / double(a.size());
}

TEST(DetectFeaturePoints, CubeEdgesCleanAndNoisy) {
  for (const double noise : {0.0, 0.2}) {
    const test::FeatureScore s = detect_and_score(test::sample_cube_features(30000), noise);
    EXPECT_GE(s.precision, 0.9) << "noise " << noise;
    EXPECT_GE(s.recall, 0.9) << "noise " << noise;
    EXPECT_GT(s.truth, 500u);
  }
}

TEST(DetectFeaturePoints, CadPartEdgesCleanAndNoisy) {
  // Right-angled convex and concave edges, two 135-degree chamfer edges and two circles.
  for (const double noise : {0.0, 0.2}) {
    const test::FeatureShape shape = test::sample_cad_part(30000);
    const test::FeatureScore s = detect_and_score(shape, noise);
    EXPECT_GE(s.precision, 0.9) << "noise " << noise;
    EXPECT_GE(s.recall, 0.9) << "noise " << noise;
  }
}

TEST(DetectFeaturePoints, ChamferEdgesAreFound) {
  // The 135-degree edges alone: points near x = -2 .. -1.75 on the part, away from other edges.
  test::FeatureShape shape = test::sample_cad_part(30000);
  const double spacing = mean_spacing(shape.cloud.positions);
  detect_feature_points(shape.cloud);
  const std::vector<double>& labels = labels_of(shape.cloud);
  std::size_t truth = 0, found = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const Vector3d& p = shape.cloud.positions[i];
    if (p.x() > -1.7 || std::abs(p.y()) > 1.3 || p.z() < 0.1 || shape.edge_distance[i] > spacing) continue;
    ++truth;
    found += labels[i] != 0.0;
  }
  ASSERT_GT(truth, 50u);
  EXPECT_GE(double(found) / double(truth), 0.9);
}

TEST(DetectFeaturePoints, CubeCornersAreLabelledNearCorners) {
  test::FeatureShape shape = test::sample_cube_features(30000);
  const double spacing = mean_spacing(shape.cloud.positions);
  const FeatureResult r = detect_feature_points(shape.cloud);
  const std::vector<double>& labels = labels_of(shape.cloud);
  std::size_t corners = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (labels[i] != double(FeatureLabel::Corner)) continue;
    ++corners;
    EXPECT_LE(shape.corner_distance[i], 3.0 * spacing) << "point " << i;
  }
  EXPECT_EQ(corners, r.corners);
  EXPECT_GE(r.corners, 4u);
  EXPECT_EQ(r.edges + r.corners, std::size_t(std::count_if(labels.begin(), labels.end(), [](double v) { return v != 0.0; })));
}

TEST(DetectFeaturePoints, EveryCubeCornerIsFoundOnSeveralSamplings) {
  // Random samples often leave no point whose own neighbourhood holds enough of each of a
  // corner's three faces; the candidates farther out still see the three planes meet there.
  // Scored as the CLI test scores it: a Corner label within 5 spacings finds a corner, none
  // lies 6 or more spacings from every corner.
  int total = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    test::FeatureShape shape = test::sample_cube_features(40000, 1.0, seed);
    const double spacing = mean_spacing(shape.cloud.positions);
    detect_feature_points(shape.cloud);
    const std::vector<double>& labels = labels_of(shape.cloud);
    std::array<bool, 8> found{};
    for (std::size_t i = 0; i < labels.size(); ++i) {
      if (labels[i] != double(FeatureLabel::Corner)) continue;
      EXPECT_LT(shape.corner_distance[i], 6.0 * spacing) << "seed " << seed << ", point " << i;
      if (shape.corner_distance[i] > 5.0 * spacing) continue;
      const Vector3d& p = shape.cloud.positions[i];
      found[(p.x() > 0) + 2 * (p.y() > 0) + 4 * (p.z() > 0)] = true;
    }
    const int corners = int(std::count(found.begin(), found.end(), true));
    std::printf("seed %d: %d of the 8 corners found\n", int(seed), corners);
    EXPECT_GE(corners, 7) << "seed " << seed;
    total += corners;
  }
  // Measured 31 of 32 (seed 2 misses one); 25 without the far-corner pass.
  EXPECT_GE(total, 31);
}

TEST(DetectFeaturePoints, SmoothSurfacesHaveAlmostNoFeatures) {
  for (const PointCloud& smooth : {test::sample_sphere(20000), test::sample_torus(20000), test::sample_plane(5000)}) {
    PointCloud cloud = smooth;
    cloud.normals.clear();
    const FeatureResult r = detect_feature_points(cloud);
    EXPECT_LE(r.edges + r.corners, cloud.size() / 200) << r.edges << " edges, " << r.corners << " corners";
  }
}

TEST(DetectFeaturePoints, FieldIsUint8AndReplacesAnExistingOne) {
  PointCloud cloud = test::sample_cube_features(8000).cloud;
  cloud.fields.add("feature", cloud.size(), ScalarType::Float64).values.assign(cloud.size(), 7.0);
  const std::vector<Vector3d> positions = cloud.positions;
  const std::vector<Vector3d> normals = cloud.normals;
  const FeatureResult r = detect_feature_points(cloud);
  const ScalarField* field = cloud.fields.find("feature");
  ASSERT_NE(field, nullptr);
  EXPECT_EQ(field->type, ScalarType::UInt8);
  ASSERT_EQ(field->values.size(), cloud.size());
  for (double v : field->values) ASSERT_TRUE(v == 0.0 || v == 1.0 || v == 2.0) << v;
  EXPECT_EQ(cloud.positions, positions);
  EXPECT_EQ(cloud.normals, normals);
  EXPECT_GE(r.candidates, r.edges + r.corners);
  EXPECT_GT(r.mean_spacing, 0.0);
  EXPECT_DOUBLE_EQ(r.dd_used, r.mean_spacing);
}

TEST(DetectFeaturePoints, ExplicitParametersAreUsedAndTreeIsReused) {
  PointCloud cloud = test::sample_cube_features(8000).cloud;
  const KdTree tree(cloud.positions);
  PointCloud with_tree = cloud;
  const FeatureResult a = detect_feature_points(with_tree, {.variation_threshold = 0.02, .plane_distance = Length::cloud(0.01)}, &tree);
  EXPECT_EQ(a.variation_threshold_used, 0.02);
  EXPECT_EQ(a.dd_used, 0.01);
  const FeatureResult b = detect_feature_points(cloud, {.variation_threshold = 0.02, .plane_distance = Length::cloud(0.01)});
  EXPECT_EQ(a.edges, b.edges);
  EXPECT_EQ(labels_of(cloud), labels_of(with_tree));
  // A plane distance in spacings scales the derived distance.
  const FeatureResult c = detect_feature_points(cloud, {.plane_distance = Length::spacings(0.5)}, &tree);
  EXPECT_DOUBLE_EQ(c.dd_used, 0.5 * c.mean_spacing);
}

TEST(DetectFeaturePoints, InputNormalsWorkUnoriented) {
  // Sharp input normals (exact ones) with random signs give the same labels as consistent signs.
  test::FeatureShape shape = test::sample_cube_features(20000);
  const double spacing = mean_spacing(shape.cloud.positions);
  PointCloud oriented = shape.cloud;
  PointCloud flipped = shape.cloud;
  std::mt19937_64 rng(11);
  for (Vector3d& n : flipped.normals)
    if (rng() % 2 == 0) n = -n;
  const FeatureParams params{.normals = FeatureNormals::Input};
  detect_feature_points(oriented, params);
  detect_feature_points(flipped, params);
  EXPECT_EQ(labels_of(oriented), labels_of(flipped));
  const test::FeatureScore s = test::score_features(labels_of(oriented), shape.edge_distance, kTruth * spacing, kTolerance * spacing);
  EXPECT_GE(s.precision, 0.9);
  EXPECT_GE(s.recall, 0.9);
}

TEST(DetectFeaturePoints, InvariantUnderPermutation) {
  const PointCloud cloud = test::sample_cad_part(20000).cloud;
  std::vector<std::size_t> perm(cloud.size());
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(5));
  PointCloud a = cloud, b = cloud.select(perm);
  detect_feature_points(a);
  detect_feature_points(b);
  std::vector<double> back(cloud.size());
  for (std::size_t i = 0; i < perm.size(); ++i) back[perm[i]] = labels_of(b)[i];
  EXPECT_LE(label_disagreement(labels_of(a), back), 1e-3);
}

TEST(DetectFeaturePoints, InvariantUnderRigidMotionAndGeoreferencedShift) {
  const PointCloud cloud = test::sample_cad_part(20000).cloud;
  PointCloud reference = cloud;
  const FeatureResult r0 = detect_feature_points(reference);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.rotate(Eigen::AngleAxisd(0.7, Vector3d(1.0, -2.0, 0.5).normalized()));
  t.pretranslate(Vector3d(12.0, -3.5, 100.0));
  PointCloud moved = cloud, shifted = cloud;
  for (Vector3d& p : moved.positions) p = t * p;
  for (Vector3d& p : shifted.positions) p += Vector3d(4.5e6, 5.3e6, 1.0e6);
  const FeatureResult r1 = detect_feature_points(moved);
  const FeatureResult r2 = detect_feature_points(shifted);
  EXPECT_LE(label_disagreement(labels_of(reference), labels_of(moved)), 1e-3);
  EXPECT_LE(label_disagreement(labels_of(reference), labels_of(shifted)), 1e-3);
  EXPECT_NEAR(double(r1.edges), double(r0.edges), 0.01 * double(r0.edges));
  EXPECT_NEAR(double(r2.edges), double(r0.edges), 0.01 * double(r0.edges));
}

TEST(DetectFeaturePoints, InvariantUnderScale) {
  // Every default derives from the mean spacing or is scale-free.
  const PointCloud cloud = test::sample_cube_features(10000).cloud;
  PointCloud small = cloud, large = cloud;
  for (Vector3d& p : small.positions) p *= 1e-3;
  for (Vector3d& p : large.positions) p *= 1e3;
  detect_feature_points(small);
  detect_feature_points(large);
  EXPECT_LE(label_disagreement(labels_of(small), labels_of(large)), 1e-3);
}

TEST(DetectFeaturePoints, CancelLeavesTheCloudUnchanged) {
  PointCloud cloud = test::sample_cube_features(8000).cloud;
  int calls = 0;
  EXPECT_THROW(detect_feature_points(cloud, {}, nullptr, [&](double) { return ++calls < 2; }), CancelledError);
  EXPECT_FALSE(cloud.fields.contains("feature"));
  double last = -1.0;
  bool monotone = true;
  detect_feature_points(cloud, {}, nullptr, [&](double f) {
    monotone = monotone && f >= last && f <= 1.0;
    last = f;
    return true;
  });
  EXPECT_TRUE(monotone);
  EXPECT_EQ(last, 1.0);
}

// A sheet folded along x = 0 by `turn_deg` (two unit-wide faces, 4 triangles), sampled by the
// issue 13 sampler: truth is the fold when it turns by 30 degrees or more.
test::FeatureShape folded_sheet(double turn_deg, std::size_t n) {
  const double t = turn_deg * std::numbers::pi / 180.0;
  TriangleMesh mesh;
  mesh.vertices.positions = {{-1, -1, 0}, {0, -1, 0}, {0, 1, 0}, {-1, 1, 0}, {std::cos(t), -1, std::sin(t)}, {std::cos(t), 1, std::sin(t)}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 2}};
  test::FeatureShape shape = test::sample_mesh_features(mesh, n, 30.0, 5);
  shape.cloud.normals.clear();
  return shape;
}

TEST(DetectFeaturePoints, ObtuseCreasesAreFoundAndShallowerFoldsAreNot) {
  // A 32-degree turn (a dihedral angle of 148 degrees): its variation, 0.0098, was under the
  // old candidate floor 0.01, so the crease was never found (issue 13's hidden CAD part).
  test::FeatureShape fold = folded_sheet(32.0, 20000);
  const double spacing = mean_spacing(fold.cloud.positions);
  const FeatureResult r = detect_feature_points(fold.cloud);
  const test::FeatureScore s = test::score_features(fold.cloud.fields.find("feature")->values, fold.edge_distance, 0.5 * spacing, 1.5 * spacing);
  std::printf("32-degree fold: precision %.3f recall %.3f (%zu labelled, %zu truth), threshold %.4f\n", s.precision, s.recall, s.labelled,
              s.truth, r.variation_threshold_used);
  EXPECT_NEAR(r.variation_threshold_used, 0.00418, 1e-4);
  EXPECT_GT(s.recall, 0.9);
  EXPECT_GT(s.precision, 0.95);
  // A 20-degree fold is below min_turn_deg (28): almost nothing is labelled.
  test::FeatureShape shallow = folded_sheet(20.0, 20000);
  detect_feature_points(shallow.cloud);
  const std::vector<double>& labels = shallow.cloud.fields.find("feature")->values;
  const auto labelled = std::count_if(labels.begin(), labels.end(), [](double v) { return v != 0.0; });
  std::printf("20-degree fold: %td of %zu labelled\n", labelled, labels.size());
  EXPECT_LT(double(labelled), 0.002 * double(labels.size()));
}

TEST(DetectFeaturePoints, BadParametersAreUsageErrors) {
  PointCloud cloud = test::sample_cube_features(2000).cloud;
  using test::expect_error;
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.k = 5}); }, "detect_feature_points: k must be >= 6, got 5");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.variation_threshold = 0.4}); },
                           "variation_threshold must be in [0, 1/3) (0: derived), got 0.4");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.variation_threshold = -0.1}); }, "got -0.1");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.cluster_angle_deg = 0.0}); }, "cluster_angle_deg must be in (0, 90) degrees, got 0");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.cluster_angle_deg = 95.0}); }, "cluster_angle_deg must be in (0, 90) degrees, got 95");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.min_turn_deg = 90.0}); }, "min_turn_deg must be in (0, 90) degrees, got 90");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.plane_distance = Length::cloud(-1.0)}); }, "plane_distance must be > 0, got -1");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.plane_distance = Length::spacings(0.0)}); }, "plane_distance must be > 0, got 0sp");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.min_cluster_points = 2}); },
                           "min_cluster_points must be in [3, k = 30], got 2");
  expect_error<UsageError>([&] { detect_feature_points(cloud, {.k = 10, .min_cluster_points = 11}); },
                           "min_cluster_points must be in [3, k = 10], got 11");
  PointCloud no_normals = cloud;
  no_normals.normals.clear();
  expect_error<UsageError>([&] { detect_feature_points(no_normals, {.normals = FeatureNormals::Input}); },
                           "normals = Input needs one normal per point, the cloud has 0 for 2000 points");
  PointCloud tiny;
  tiny.positions.assign(10, Vector3d::Zero());
  expect_error<UsageError>([&] { detect_feature_points(tiny); }, "needs at least k + 1 = 31 points, got 10");
  const KdTree other(tiny.positions);
  expect_error<UsageError>([&] { detect_feature_points(cloud, {}, &other); }, "the kd-tree holds 10 points but the cloud has 2000");
  EXPECT_FALSE(cloud.fields.contains("feature"));
}

}  // namespace
}  // namespace pointsurf
