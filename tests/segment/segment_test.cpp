// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/segment/segment.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/shape/curvature.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

// For each truth class: the share of its points in its most common label, and that label.
std::vector<std::pair<double, int>> majority(const std::vector<int>& truth, const std::vector<std::int32_t>& labels, int classes) {
  std::vector<std::map<int, std::size_t>> counts(static_cast<std::size_t>(classes));
  std::vector<std::size_t> totals(std::size_t(classes), 0);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (truth[i] < 0) continue;
    ++counts[std::size_t(truth[i])][labels[i]];
    ++totals[std::size_t(truth[i])];
  }
  std::vector<std::pair<double, int>> out;
  for (int t = 0; t < classes; ++t) {
    auto best = std::max_element(counts[std::size_t(t)].begin(), counts[std::size_t(t)].end(),
                                 [](auto& a, auto& b) { return a.second < b.second; });
    out.emplace_back(double(best->second) / double(totals[std::size_t(t)]), best->first);
  }
  return out;
}

// The cube's face of each point (0..5), from its exact position.
std::vector<int> cube_faces(const PointCloud& cube, double half) {
  std::vector<int> face(cube.size());
  for (std::size_t i = 0; i < cube.size(); ++i) {
    int axis = 0;
    cube.positions[i].cwiseAbs().maxCoeff(&axis);
    face[i] = 2 * axis + (cube.positions[i][axis] > 0.0 ? 0 : 1);
    (void)half;
  }
  return face;
}

PointCloud estimated_cube(std::size_t n) {
  PointCloud cube = test::sample_cube(n, 1.0, 5);
  cube.normals.clear();
  NormalParams p;
  p.k = 16;
  estimate_normals(cube, p);
  return cube;
}

// A seeded permutation of 0 .. n-1.
std::vector<std::size_t> shuffled(std::size_t n, std::uint64_t seed) {
  std::vector<std::size_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(seed));
  return perm;
}

// Labels of a permuted cloud must be the base labels, permuted: segments are numbered by size
// and position, not by point order.
void expect_permuted(const SegmentResult& base, const SegmentResult& permuted, const std::vector<std::size_t>& perm) {
  ASSERT_EQ(permuted.labels.size(), perm.size());
  for (std::size_t i = 0; i < perm.size(); ++i) ASSERT_EQ(permuted.labels[i], base.labels[perm[i]]) << i;
  EXPECT_EQ(permuted.sizes, base.sizes);
}

// Share of points with the same label in two results over the same points.
double same_share(const SegmentResult& a, const SegmentResult& b) {
  std::size_t same = 0;
  for (std::size_t i = 0; i < a.labels.size(); ++i) same += a.labels[i] == b.labels[i];
  return double(same) / double(a.labels.size());
}

TEST(RegionGrowing, SeparatesTheSixFacesOfACube) {
  const PointCloud cube = estimated_cube(30000);
  const SegmentResult r = segment_region_growing(cube);
  const auto major = majority(cube_faces(cube, 1.0), r.labels, 6);
  std::vector<int> seen;
  for (int f = 0; f < 6; ++f) {
    SCOPED_TRACE(f);
    EXPECT_GE(major[std::size_t(f)].first, 0.9);
    EXPECT_GE(major[std::size_t(f)].second, 0);
    seen.push_back(major[std::size_t(f)].second);
  }
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::unique(seen.begin(), seen.end()), seen.end()) << "two faces share a segment";
  EXPECT_GE(r.sizes.size(), 6u);
}

TEST(RegionGrowing, FeaturePointsAreBarriers) {
  // Two coplanar halves joined only through a strip of feature points: with the barrier the
  // strip cannot carry a region across, without it one region covers both.
  PointCloud plane = test::sample_plane(8000, 1.0, 3);
  std::vector<double>& feature = plane.fields.add("feature", plane.size()).values;
  for (std::size_t i = 0; i < plane.size(); ++i) feature[i] = std::abs(plane.positions[i].x()) < 0.1;
  const SegmentResult with = segment_region_growing(plane);
  RegionGrowingParams off;
  off.use_features = false;
  const SegmentResult without = segment_region_growing(plane, off);
  EXPECT_EQ(without.sizes.size(), 1u);
  std::set<int> left, right;
  for (std::size_t i = 0; i < plane.size(); ++i) {
    if (plane.positions[i].x() < -0.2) left.insert(with.labels[i]);
    if (plane.positions[i].x() > 0.2) right.insert(with.labels[i]);
  }
  ASSERT_EQ(left.size(), 1u);
  ASSERT_EQ(right.size(), 1u);
  EXPECT_NE(*left.begin(), *right.begin());
}

TEST(RegionGrowing, InvariantUnderPermutationAndShift) {
  const PointCloud cube = estimated_cube(8000);
  const SegmentResult base = segment_region_growing(cube);
  const std::vector<std::size_t> perm = shuffled(cube.size(), 9);
  expect_permuted(base, segment_region_growing(cube.select(perm)), perm);
  PointCloud shifted = cube;
  for (Vector3d& x : shifted.positions) x += Vector3d(1e6, 1e6, -1e6);
  EXPECT_GT(same_share(base, segment_region_growing(shifted)), 0.99);
}

// Three Gaussian blobs (3000, 2000, 1000 points, sigma 0.1) 3 apart and a lone point far off
// (truth -1).
PointCloud three_blobs(std::vector<int>& truth) {
  PointCloud cloud;
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g(0.0, 0.1);
  const Vector3d centres[3] = {{0, 0, 0}, {3, 0, 0}, {0, 3, 0}};
  const int counts[3] = {3000, 2000, 1000};
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < counts[c]; ++i) {
      const double x = g(rng), y = g(rng), z = g(rng);
      cloud.positions.push_back(centres[c] + Vector3d(x, y, z));
      truth.push_back(c);
    }
  cloud.positions.emplace_back(10, 10, 10);
  truth.push_back(-1);
  return cloud;
}

TEST(Euclidean, SeparatesBlobsAndDropsSmallOnes) {
  std::vector<int> truth;
  const PointCloud cloud = three_blobs(truth);
  EuclideanParams p;
  p.radius = Length::cloud(0.3);
  const SegmentResult r = segment_euclidean(cloud, p);
  ASSERT_EQ(r.sizes.size(), 3u);
  EXPECT_EQ(r.sizes, (std::vector<std::size_t>{3000, 2000, 1000}));
  for (std::size_t i = 0; i + 1 < cloud.size(); ++i) ASSERT_EQ(r.labels[i], truth[i]);
  EXPECT_EQ(r.labels.back(), -1);
  EXPECT_EQ(r.unassigned, 1u);
  // The default radius (3 mean spacings) keeps the blobs apart too.
  EXPECT_EQ(segment_euclidean(cloud).sizes.size(), 3u);
}

TEST(Euclidean, InvariantUnderPermutationAndShift) {
  std::vector<int> truth;
  const PointCloud cloud = three_blobs(truth);
  EuclideanParams p;
  p.radius = Length::cloud(0.15);  // the blobs' cores stay joined; fewer neighbours than 0.3 keep the test short
  const SegmentResult base = segment_euclidean(cloud, p);
  const std::vector<std::size_t> perm = shuffled(cloud.size(), 9);
  expect_permuted(base, segment_euclidean(cloud.select(perm), p), perm);
  PointCloud shifted = cloud;
  for (Vector3d& x : shifted.positions) x += Vector3d(1e6, -1e6, 1e6);
  const SegmentResult s = segment_euclidean(shifted, p);
  EXPECT_EQ(s.sizes, base.sizes);
  EXPECT_GE(same_share(base, s), 0.999);
}

// A torus (R 1, r 0.3) of n points with its HK surface_type field (jet fit, k 30).
PointCloud typed_torus(std::size_t n) {
  PointCloud torus = test::sample_torus(n, 1.0, 0.3, 4);
  CurvatureParams cp;
  cp.k = 30;
  estimate_curvature(torus, cp);
  return torus;
}

TEST(SurfaceTypes, TorusGivesAnEllipticAndAHyperbolicBand) {
  const PointCloud torus = typed_torus(40000);
  const SegmentResult r = segment_surface_types(torus);
  // Truth from the tube angle v: cos v > 0 elliptic (outer), < 0 hyperbolic (inner); points
  // within 0.3 rad of the parabolic circles are left out.
  std::vector<int> truth(torus.size());
  for (std::size_t i = 0; i < torus.size(); ++i) {
    const Vector3d& p = torus.positions[i];
    const double rho = std::hypot(p.x(), p.y()) - 1.0;
    const double v = std::atan2(p.z(), rho);
    truth[i] = std::abs(std::cos(v)) < std::sin(0.3) ? -1 : (std::cos(v) > 0 ? 0 : 1);
  }
  const auto major = majority(truth, r.labels, 2);
  EXPECT_GE(major[0].first, 0.9);
  EXPECT_GE(major[1].first, 0.9);
  ASSERT_GE(major[0].second, 0);
  ASSERT_GE(major[1].second, 0);
  EXPECT_NE(major[0].second, major[1].second);
  const std::vector<double>& type = torus.fields.find("surface_type")->values;
  std::map<int, std::size_t> outer, inner;
  for (std::size_t i = 0; i < torus.size(); ++i) {
    if (r.labels[i] == major[0].second) ++outer[int(type[i])];
    if (r.labels[i] == major[1].second) ++inner[int(type[i])];
  }
  EXPECT_EQ(outer.size(), 1u);
  EXPECT_EQ(outer.begin()->first, int(SurfaceType::Peak));
  EXPECT_EQ(inner.size(), 1u);
  EXPECT_EQ(inner.begin()->first, int(SurfaceType::SaddleRidge));
}

TEST(SurfaceTypes, InvariantUnderPermutationAndShift) {
  const PointCloud torus = typed_torus(20000);
  const SegmentResult base = segment_surface_types(torus);
  ASSERT_GE(base.sizes.size(), 2u);
  const std::vector<std::size_t> perm = shuffled(torus.size(), 5);
  expect_permuted(base, segment_surface_types(torus.select(perm)), perm);
  PointCloud shifted = torus;  // the same surface_type field, the positions 1e6 m away
  for (Vector3d& x : shifted.positions) x += Vector3d(-1e6, 1e6, 1e6);
  EXPECT_GE(same_share(base, segment_surface_types(shifted)), 0.99);
}

TEST(Segment, EmptyCloudsAndBadInputs) {
  EXPECT_TRUE(segment_region_growing(PointCloud{}).labels.empty());
  EXPECT_TRUE(segment_euclidean(PointCloud{}).labels.empty());
  EXPECT_TRUE(segment_surface_types(PointCloud{}).labels.empty());
  PointCloud bare = test::sample_plane(50);
  bare.normals.clear();
  EXPECT_THROW(segment_region_growing(bare), UsageError);
  try {
    segment_surface_types(bare);
    FAIL() << "no throw";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("surface_type"), std::string::npos);
  }
  RegionGrowingParams rg;
  rg.k = 2;
  EXPECT_THROW(rg.validate(), UsageError);
  rg = {};
  rg.max_angle_deg = 0.0;
  EXPECT_THROW(rg.validate(), UsageError);
  rg = {};
  rg.max_variation = 0.5;
  EXPECT_THROW(rg.validate(), UsageError);
  EuclideanParams e;
  e.radius = Length::cloud(-1.0);
  EXPECT_THROW(e.validate(), UsageError);
  e.radius = Length::spacings(0.0);
  test::expect_error<UsageError>([&] { e.validate(); }, "segment_euclidean: radius must be > 0, got 0sp");
  SurfaceTypeParams s;
  s.k = 1;
  EXPECT_THROW(s.validate(), UsageError);
  // A flat cloud is one region; points all at one place are one Euclidean cluster.
  EXPECT_EQ(segment_region_growing(test::sample_plane(2000)).sizes.size(), 1u);
  PointCloud same;
  same.positions.assign(20, Vector3d(1, 1, 1));
  EXPECT_EQ(segment_euclidean(same).sizes, std::vector<std::size_t>{20});
}

}  // namespace
}  // namespace pointsurf
