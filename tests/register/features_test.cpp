// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/features.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/rigid_transform.h"
#include "pointsurf/io/io.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/scan_views.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

Descriptors describe(const PointCloud& cloud, DescriptorType type, double radius_in_spacings = 10.0, std::size_t max_neighbors = 100) {
  const KdTree tree(cloud.positions);
  DescriptorParams params;
  params.type = type;
  params.radius = Length::spacings(radius_in_spacings);
  params.max_neighbors = max_neighbors;
  return compute_descriptors(cloud, tree, params);
}

// --- A brute-force oracle, in double, written from the papers' definitions. -----------------

// The Darboux-frame triple (alpha, phi, theta) of a pair, the source being the point whose
// normal is closer to the line (Rusu 2008, section IV; PCL's computePairFeatures).
bool oracle_pair(const Vector3d& p1, const Vector3d& n1, const Vector3d& p2, const Vector3d& n2, double f[3]) {
  Vector3d d = p2 - p1;
  const double len = d.norm();
  if (len == 0.0) return false;
  const double a1 = n1.dot(d) / len, a2 = n2.dot(d) / len;
  Vector3d u = n1, nt = n2;
  double theta = a1;
  if (std::acos(std::abs(a1)) > std::acos(std::abs(a2))) {
    u = n2;
    nt = n1;
    d = -d;
    theta = -a2;
  }
  Vector3d v = d.cross(u);
  if (v.norm() == 0.0) return false;
  v.normalize();
  const Vector3d w = u.cross(v);
  f[0] = std::atan2(w.dot(nt), u.dot(nt));
  f[1] = v.dot(nt);
  f[2] = theta;
  return true;
}

int oracle_bin(double fraction, int bins) { return std::clamp(int(std::floor(bins * fraction)), 0, bins - 1); }

// Neighbours of point i by brute force: at most k nearest within r (the point included),
// nearest first, ties by index.
std::vector<std::size_t> oracle_neighbors(const PointCloud& c, std::size_t i, double r, std::size_t k) {
  std::vector<std::size_t> all;
  for (std::size_t j = 0; j < c.size(); ++j)
    if ((c.positions[j] - c.positions[i]).norm() <= r) all.push_back(j);
  std::sort(all.begin(), all.end(), [&](std::size_t a, std::size_t b) {
    const double da = (c.positions[a] - c.positions[i]).squaredNorm(), db = (c.positions[b] - c.positions[i]).squaredNorm();
    return da < db || (da == db && a < b);
  });
  if (all.size() > k) all.resize(k);
  return all;
}

std::vector<double> oracle_pfh(const PointCloud& c, std::size_t i, double r, std::size_t k) {
  const std::vector<std::size_t> nb = oracle_neighbors(c, i, r, k);
  std::vector<double> h(125, 0.0);
  std::size_t pairs = 0;
  for (std::size_t a = 0; a < nb.size(); ++a)
    for (std::size_t b = 0; b < a; ++b) {
      double f[3];
      if (!oracle_pair(c.positions[nb[a]], c.normals[nb[a]], c.positions[nb[b]], c.normals[nb[b]], f)) continue;
      const int bin = oracle_bin((f[0] + std::numbers::pi) / (2 * std::numbers::pi), 5) + 5 * oracle_bin((f[1] + 1) / 2, 5) +
                      25 * oracle_bin((f[2] + 1) / 2, 5);
      h[bin] += 1.0;
      ++pairs;
    }
  for (double& x : h) x *= 100.0 / double(pairs);
  return h;
}

std::vector<double> oracle_spfh(const PointCloud& c, std::size_t i, double r, std::size_t k) {
  std::vector<double> h(33, 0.0);
  std::size_t pairs = 0;
  for (std::size_t j : oracle_neighbors(c, i, r, k)) {
    double f[3];
    if (j == i || !oracle_pair(c.positions[i], c.normals[i], c.positions[j], c.normals[j], f)) continue;
    h[oracle_bin((f[0] + std::numbers::pi) / (2 * std::numbers::pi), 11)] += 1.0;
    h[11 + oracle_bin((f[1] + 1) / 2, 11)] += 1.0;
    h[22 + oracle_bin((f[2] + 1) / 2, 11)] += 1.0;
    ++pairs;
  }
  for (double& x : h) x *= 100.0 / double(pairs);
  return h;
}

// FPFH(i) = SPFH(i) + each third of sum_j SPFH(j) / d_ij^2 scaled to sum to 100 (Rusu 2009,
// eq. 4, with PCL's and Open3D's squared-distance weights).
std::vector<double> oracle_fpfh(const PointCloud& c, std::size_t i, double r, std::size_t k) {
  std::vector<double> sum(33, 0.0), out = oracle_spfh(c, i, r, k);
  for (std::size_t j : oracle_neighbors(c, i, r, k)) {
    if (j == i) continue;
    const std::vector<double> s = oracle_spfh(c, j, r, k);
    const double w = 1.0 / (c.positions[j] - c.positions[i]).squaredNorm();
    for (int b = 0; b < 33; ++b) sum[b] += w * s[b];
  }
  for (int part = 0; part < 3; ++part) {
    double total = 0.0;
    for (int b = 0; b < 11; ++b) total += sum[part * 11 + b];
    for (int b = 0; b < 11; ++b) out[part * 11 + b] += 100.0 * sum[part * 11 + b] / total;
  }
  return out;
}

double l1(std::span<const float> a, const std::vector<double>& b) {
  double s = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) s += std::abs(double(a[k]) - b[k]);
  return s;
}

double l1(std::span<const float> a, std::span<const float> b) {
  double s = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) s += std::abs(double(a[k]) - double(b[k]));
  return s;
}

// Rows i of `a` and rows map[i] of `b` agree: a bin may flip for a pair whose feature sits on a
// bin edge (float rounding of moved coordinates), so most rows must be identical up to float
// round-off and the rest close.
void expect_same_rows(const Descriptors& a, const Descriptors& b, const std::vector<std::size_t>& map) {
  ASSERT_EQ(a.size(), map.size());
  std::size_t differ = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.valid[i], b.valid[map[i]]) << "point " << i;
    const double d = l1(a.row(i), b.row(map[i]));
    if (d > 1e-3) ++differ;
    worst = std::max(worst, d);
  }
  EXPECT_LE(differ, a.size() / 100) << "rows that differ";
  EXPECT_LT(worst, 20.0);  // of a row total of 100 (PFH) or 600 (FPFH)
}

// --- Known answers. ---------------------------------------------------------------------------

TEST(Descriptors, PlaneConcentratesInTheMiddleBins) {
  // On a plane every pair has n1 = n2 perpendicular to the line: alpha = phi = theta = 0, the
  // middle bin of each feature (5 of 11; 2 of 5, so PFH bin 2 + 5 * 2 + 25 * 2 = 62).
  const PointCloud plane = test::sample_plane(3000, 1.0, 3);
  const Descriptors fpfh = describe(plane, DescriptorType::Fpfh);
  ASSERT_EQ(fpfh.dimension, 33u);
  const Descriptors pfh = describe(plane, DescriptorType::Pfh);
  ASSERT_EQ(pfh.dimension, 125u);
  for (std::size_t i = 0; i < plane.size(); ++i) {
    ASSERT_TRUE(fpfh.valid[i]);
    ASSERT_TRUE(pfh.valid[i]);
    for (std::size_t b = 0; b < 33; ++b)
      ASSERT_NEAR(fpfh.row(i)[b], (b == 5 || b == 16 || b == 27) ? 200.0f : 0.0f, 1e-3f) << "point " << i << " bin " << b;
    for (std::size_t b = 0; b < 125; ++b) ASSERT_NEAR(pfh.row(i)[b], b == 62 ? 100.0f : 0.0f, 1e-3f) << "point " << i << " bin " << b;
  }
  EXPECT_NEAR(fpfh.radius, 10.0 * mean_spacing(plane.positions), 1e-12);
}

TEST(Descriptors, PfhAndFpfhAgreeWithABruteForceOracle) {
  const PointCloud cloud = test::kitten();
  const double radius = 10.0 * mean_spacing(cloud.positions);
  const Descriptors pfh = describe(cloud, DescriptorType::Pfh);
  const Descriptors fpfh = describe(cloud, DescriptorType::Fpfh);
  for (std::size_t i : {0ul, 17ul, 999ul, 2500ul, 5209ul}) {
    ASSERT_TRUE(pfh.valid[i]);
    ASSERT_TRUE(fpfh.valid[i]);
    // A pair on a bin edge may fall either side in float: one pair moves 100 / pairs twice.
    EXPECT_LT(l1(pfh.row(i), oracle_pfh(cloud, i, radius, 100)), 0.2) << "PFH of point " << i;
    EXPECT_LT(l1(fpfh.row(i), oracle_fpfh(cloud, i, radius, 100)), 0.5) << "FPFH of point " << i;
  }
}

TEST(Descriptors, InvariantUnderRigidMotionAndAFarShift) {
  const PointCloud cloud = test::kitten();
  PointCloud moved = cloud;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(1.1, Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  RigidTransform(r, Vector3d(1e6, -2e6, 5e5)).apply(moved);
  std::vector<std::size_t> identity(cloud.size());
  std::iota(identity.begin(), identity.end(), std::size_t(0));
  for (DescriptorType type : {DescriptorType::Fpfh, DescriptorType::Pfh}) {
    SCOPED_TRACE(descriptor_type_name(type));
    const Descriptors a = describe(cloud, type, 8.0, 60);
    const Descriptors b = describe(moved, type, 8.0, 60);
    EXPECT_NEAR(a.radius, b.radius, 1e-6 * a.radius);
    expect_same_rows(a, b, identity);
  }
}

TEST(Descriptors, InvariantUnderPermutation) {
  const PointCloud cloud = test::kitten();
  std::vector<std::size_t> perm(cloud.size());
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(11));
  const PointCloud shuffled = cloud.select(perm);  // shuffled[k] = cloud[perm[k]]
  std::vector<std::size_t> where(cloud.size());
  for (std::size_t k = 0; k < perm.size(); ++k) where[perm[k]] = k;
  for (DescriptorType type : {DescriptorType::Fpfh, DescriptorType::Pfh}) {
    SCOPED_TRACE(descriptor_type_name(type));
    expect_same_rows(describe(cloud, type, 8.0, 60), describe(shuffled, type, 8.0, 60), where);
  }
}

TEST(Descriptors, ZeroNormalsAndIsolatedPointsAreInvalid) {
  PointCloud cloud = test::sample_plane(500, 1.0, 5);
  cloud.normals[7] = Vector3d::Zero();
  cloud.positions.emplace_back(50.0, 50.0, 0.0);  // far from everything
  cloud.normals.emplace_back(0.0, 0.0, 1.0);
  for (DescriptorType type : {DescriptorType::Fpfh, DescriptorType::Pfh}) {
    const Descriptors d = describe(cloud, type);
    EXPECT_EQ(d.valid[7], 0);
    EXPECT_EQ(d.valid[500], 0);
    EXPECT_EQ(d.valid[8], 1);
    for (float x : d.row(7)) EXPECT_EQ(x, 0.0f);
    for (float x : d.row(500)) EXPECT_EQ(x, 0.0f);
  }
  // Three points: no neighbourhood can hold 3 neighbours.
  PointCloud tiny;
  tiny.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  tiny.normals.assign(3, Vector3d(0, 0, 1));
  const Descriptors d = describe(tiny, DescriptorType::Fpfh);
  EXPECT_EQ(d.size(), 3u);
  EXPECT_EQ(std::count(d.valid.begin(), d.valid.end(), 1), 0);
}

TEST(Descriptors, ProgressReachesOneAndCancels) {
  const PointCloud cloud = test::sample_sphere(2000);
  const KdTree tree(cloud.positions);
  double last = -1.0;
  bool monotone = true;
  compute_descriptors(cloud, tree, {}, [&](double f) {
    monotone = monotone && f >= last;
    last = f;
    return true;
  });
  EXPECT_TRUE(monotone);
  EXPECT_EQ(last, 1.0);
  EXPECT_THROW(compute_descriptors(cloud, tree, {}, [](double) { return false; }), CancelledError);
}

TEST(Descriptors, BadInputThrowsUsageError) {
  PointCloud cloud = test::sample_sphere(200);
  const KdTree tree(cloud.positions);
  const auto expect_usage = [&](const PointCloud& c, const DescriptorParams& p, const std::string& text) {
    try {
      compute_descriptors(c, tree, p);
      ADD_FAILURE() << "no error for " << text;
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  DescriptorParams p;
  p.radius = Length::cloud(-1.0);
  expect_usage(cloud, p, "compute_descriptors: radius must be > 0, got -1");
  p = {};
  p.radius = Length::spacings(0.0);
  expect_usage(cloud, p, "compute_descriptors: radius must be > 0, got 0sp");
  p = {};
  p.max_neighbors = 3;
  expect_usage(cloud, p, "max_neighbors must be >= 4");
  p = {};
  p.type = static_cast<DescriptorType>(7);
  expect_usage(cloud, p, "unknown descriptor type");
  PointCloud bare = cloud;
  bare.normals.clear();
  expect_usage(bare, {}, "no normals");
  PointCloud fewer = cloud;
  fewer.positions.pop_back();
  fewer.normals.pop_back();
  expect_usage(fewer, {}, "kd-tree holds 200 points but the cloud has 199");
  EXPECT_STREQ(descriptor_type_name(DescriptorType::Pfh), "pfh");
  EXPECT_STREQ(descriptor_type_name(DescriptorType::Fpfh), "fpfh");
}

}  // namespace
}  // namespace pointsurf
