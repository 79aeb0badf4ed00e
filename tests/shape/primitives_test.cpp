// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/shape/primitives.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "pointsurf/core/error.h"
#include "support/primitive_scene.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

double axis_angle_deg(const Vector3d& a, const Vector3d& b) {
  return std::acos(std::clamp(std::abs(a.dot(b)), 0.0, 1.0)) * 180.0 / M_PI;
}

// Whether `found` describes `truth` within 1 degree and 1 % of the scene size.
bool matches(const Primitive& found, const Primitive& truth, double size) {
  if (found.type != truth.type) return false;
  const double tol = 0.01 * size;
  switch (truth.type) {
    case PrimitiveType::Plane:
      return axis_angle_deg(found.axis, truth.axis) < 1.0 && std::abs(truth.axis.dot(found.point - truth.point)) < tol;
    case PrimitiveType::Sphere:
      return (found.point - truth.point).norm() < tol && std::abs(found.radius - truth.radius) < tol;
    case PrimitiveType::Cylinder: {
      const Vector3d d = found.point - truth.point;
      return axis_angle_deg(found.axis, truth.axis) < 1.0 && (d - d.dot(truth.axis) * truth.axis).norm() < tol &&
             std::abs(found.radius - truth.radius) < tol;
    }
    case PrimitiveType::Cone:
      return axis_angle_deg(found.axis, truth.axis) < 1.0 && found.axis.dot(truth.axis) > 0.0 && (found.point - truth.point).norm() < tol &&
             std::abs(found.angle_deg - truth.angle_deg) < 1.0;
    case PrimitiveType::Torus:
      return axis_angle_deg(found.axis, truth.axis) < 1.0 && (found.point - truth.point).norm() < tol && std::abs(found.radius - truth.radius) < tol &&
             std::abs(found.minor_radius - truth.minor_radius) < tol;
  }
  return false;
}

// For each truth primitive: the share of its points in its most common label, and that label.
std::vector<std::pair<double, int>> majority(const PointCloud& cloud, const std::vector<std::int32_t>& labels, std::size_t truths) {
  const std::vector<double>& truth = cloud.fields.find("truth")->values;
  std::vector<std::map<int, std::size_t>> counts(truths);
  std::vector<std::size_t> totals(truths, 0);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    ++counts[std::size_t(truth[i])][labels[i]];
    ++totals[std::size_t(truth[i])];
  }
  std::vector<std::pair<double, int>> out;
  for (std::size_t t = 0; t < truths; ++t) {
    auto best = std::max_element(counts[t].begin(), counts[t].end(), [](auto& a, auto& b) { return a.second < b.second; });
    out.emplace_back(double(best->second) / double(totals[t]), best->first);
  }
  return out;
}

TEST(DetectPrimitives, RecoversEachPrimitiveOfTheScene) {
  const test::PrimitiveScene scene = test::make_primitive_scene();
  for (const unsigned types : {unsigned(kDefaultPrimitives), unsigned(kAllPrimitives)}) {
    SCOPED_TRACE(testing::Message() << "types " << types);
    PrimitiveParams params;
    params.types = types;
    const PrimitiveResult r = detect_primitives(scene.cloud, params);
    ASSERT_EQ(r.labels.size(), scene.cloud.size());
    const auto major = majority(scene.cloud, r.labels, scene.truth.size());
    for (std::size_t t = 0; t < scene.truth.size(); ++t) {
      SCOPED_TRACE(testing::Message() << "truth " << t << " (" << primitive_type_name(scene.truth[t].type) << ")");
      EXPECT_GE(major[t].first, 0.95);
      ASSERT_GE(major[t].second, 0);
      const Primitive& found = r.primitives[std::size_t(major[t].second)];
      EXPECT_TRUE(matches(found, scene.truth[t], scene.size))
          << primitive_type_name(found.type) << " point " << found.point.transpose() << " axis " << found.axis.transpose() << " radius "
          << found.radius << " angle " << found.angle_deg;
      EXPECT_LT(found.rms, 0.01);
    }
    EXPECT_EQ(r.primitives.size(), scene.truth.size());
  }
}

// A torus sampled uniformly by area with noise `sigma` along the normal, appended to `cloud`
// with truth label `label`.
void add_torus(PointCloud& cloud, const Primitive& torus, double per_unit_area, double sigma, int label, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma);
  const Vector3d x = (std::abs(torus.axis.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY()).cross(torus.axis).normalized();
  const Vector3d y = torus.axis.cross(x);
  const double R = torus.radius, r = torus.minor_radius;
  std::vector<double>& truth = cloud.fields.contains("truth") ? cloud.fields.find("truth")->values : cloud.fields.add("truth", cloud.size()).values;
  for (std::size_t i = 0, n = std::size_t(4 * M_PI * M_PI * R * r * per_unit_area); i < n;) {
    const double a = 2 * M_PI * u(rng), b = 2 * M_PI * u(rng);
    if (u(rng) * (R + r) > R + r * std::cos(b)) continue;  // area element (R + r cos b)
    const Vector3d radial = std::cos(a) * x + std::sin(a) * y;
    const Vector3d normal = std::cos(b) * radial + std::sin(b) * torus.axis;
    cloud.positions.push_back(torus.point + R * radial + r * normal + noise(rng) * normal);
    cloud.normals.push_back(normal);
    truth.push_back(label);
    ++i;
  }
}

TEST(DetectPrimitives, RecoversANoisyTorus) {
  Primitive torus{PrimitiveType::Torus, Vector3d(0.3, -0.2, 0.5), Vector3d(0.2, -0.3, 1.0).normalized(), 2.0};
  torus.minor_radius = 0.6;
  PointCloud cloud;
  add_torus(cloud, torus, 250.0, 0.005, 0, 5);
  PrimitiveParams params;
  params.types = kAllPrimitives;
  const PrimitiveResult r = detect_primitives(cloud, params);
  const auto major = majority(cloud, r.labels, 1);
  EXPECT_GE(major[0].first, 0.95);
  ASSERT_GE(major[0].second, 0);
  const Primitive& found = r.primitives[std::size_t(major[0].second)];
  EXPECT_TRUE(matches(found, torus, 2.0 * (torus.radius + torus.minor_radius)))
      << primitive_type_name(found.type) << " centre " << found.point.transpose() << " axis " << found.axis.transpose() << " radii "
      << found.radius << " " << found.minor_radius;
  EXPECT_LT(found.rms, 0.01);
  // Without the torus model no primitive holds it.
  params.types = kDefaultPrimitives;
  const auto without = majority(cloud, detect_primitives(cloud, params).labels, 1);
  EXPECT_FALSE(without[0].first >= 0.95 && without[0].second >= 0);
}

TEST(DetectPrimitives, TorusBesidePlanesIsOneSegment) {
  test::PrimitiveScene scene = test::make_primitive_scene();
  // Keep the ground and the wall, add a tilted torus clear of both.
  std::vector<std::size_t> planes;
  const std::vector<double>& truth = scene.cloud.fields.find("truth")->values;
  for (std::size_t i = 0; i < scene.cloud.size(); ++i)
    if (truth[i] <= 1.0) planes.push_back(i);
  PointCloud cloud = scene.cloud.select(planes);
  Primitive torus{PrimitiveType::Torus, Vector3d(-0.5, -1.0, 2.5), Vector3d(0.5, 0.0, 1.0).normalized(), 1.5};
  torus.minor_radius = 0.4;
  add_torus(cloud, torus, 300.0, 0.005, 2, 6);
  PrimitiveParams params;
  params.types = kAllPrimitives;
  const PrimitiveResult r = detect_primitives(cloud, params);
  const std::vector<Primitive> truths = {scene.truth[0], scene.truth[1], torus};
  const auto major = majority(cloud, r.labels, truths.size());
  for (std::size_t t = 0; t < truths.size(); ++t) {
    SCOPED_TRACE(testing::Message() << "truth " << t << " (" << primitive_type_name(truths[t].type) << ")");
    EXPECT_GE(major[t].first, 0.95);
    ASSERT_GE(major[t].second, 0);
    EXPECT_TRUE(matches(r.primitives[std::size_t(major[t].second)], truths[t], scene.size));
  }
  EXPECT_EQ(r.primitives.size(), truths.size());
}

TEST(DetectPrimitives, InvariantUnderPermutationAndShift) {
  const test::PrimitiveScene scene = test::make_primitive_scene(150.0);
  const PrimitiveResult base = detect_primitives(scene.cloud);
  std::vector<std::size_t> perm(scene.cloud.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(3));
  const PointCloud permuted = scene.cloud.select(perm);
  const PrimitiveResult p = detect_primitives(permuted);
  ASSERT_EQ(p.primitives.size(), base.primitives.size());
  for (std::size_t i = 0; i < perm.size(); ++i) ASSERT_EQ(p.labels[i], base.labels[perm[i]]) << i;

  PointCloud shifted = scene.cloud;
  const Vector3d shift(1e6, -1e6, 1e6);
  for (Vector3d& x : shifted.positions) x += shift;
  const PrimitiveResult s = detect_primitives(shifted);
  ASSERT_EQ(s.primitives.size(), base.primitives.size());
  std::size_t same = 0;
  for (std::size_t i = 0; i < perm.size(); ++i) same += s.labels[i] == base.labels[i];
  EXPECT_GT(double(same), 0.99 * double(perm.size()));
  for (std::size_t k = 0; k < s.primitives.size(); ++k) {
    Primitive moved = base.primitives[k];
    moved.point += shift;
    EXPECT_TRUE(matches(s.primitives[k], moved, 1.0)) << k;
  }
}

TEST(DetectPrimitives, DeterministicForASeedWhateverTheThreads) {
  const test::PrimitiveScene scene = test::make_primitive_scene(100.0);
  PrimitiveParams params;
  params.types = kAllPrimitives;
  const PrimitiveResult base = detect_primitives(scene.cloud, params);
  EXPECT_EQ(detect_primitives(scene.cloud, params).labels, base.labels);
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    EXPECT_EQ(detect_primitives(scene.cloud, params).labels, base.labels);
  }
  params.seed = 7;
  EXPECT_EQ(detect_primitives(scene.cloud, params).primitives.size(), base.primitives.size());
}

TEST(DetectPrimitives, ReportsProgressAndCancels) {
  const test::PrimitiveScene scene = test::make_primitive_scene(100.0);
  std::vector<double> seen;
  detect_primitives(scene.cloud, {}, [&](double f) {
    seen.push_back(f);
    return true;
  });
  ASSERT_FALSE(seen.empty());
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_GE(seen.front(), 0.0);
  EXPECT_LE(seen.back(), 1.0);
  EXPECT_GT(seen.back(), 0.9);  // the five primitives hold nearly every point
  int calls = 0;
  EXPECT_THROW(detect_primitives(scene.cloud, {}, [&](double) { return ++calls < 3; }), CancelledError);
  EXPECT_EQ(calls, 3);
}

TEST(DetectPrimitives, FlatCloudGivesOnePlane) {
  PointCloud plane = test::sample_plane(5000, 1.0, 4);
  plane.normals.assign(plane.size(), Vector3d::UnitZ());
  const PrimitiveResult r = detect_primitives(plane);
  ASSERT_EQ(r.primitives.size(), 1u);
  EXPECT_EQ(r.primitives[0].type, PrimitiveType::Plane);
  EXPECT_GT(r.primitives[0].inliers, 4900u);
}

TEST(DetectPrimitives, EmptyAndDegenerateCloudsGiveNoPrimitive) {
  EXPECT_TRUE(detect_primitives(PointCloud{}).primitives.empty());
  PointCloud same;
  same.positions.assign(100, Vector3d(1, 2, 3));
  same.normals.assign(100, Vector3d::UnitZ());
  const PrimitiveResult r = detect_primitives(same);
  EXPECT_TRUE(r.primitives.empty());
  EXPECT_EQ(r.unassigned, 100u);
}

TEST(DetectPrimitives, RejectsBadParametersAndMissingNormals) {
  PointCloud plane = test::sample_plane(100);
  plane.normals.clear();
  try {
    detect_primitives(plane);
    FAIL() << "no throw";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("no normals"), std::string::npos);
  }
  PrimitiveParams p;
  p.max_normal_deg = 95.0;
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.types = 0;
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.epsilon = -1.0;
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.probability = 1.0;
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.types = 32;
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.band_in_epsilons = 0.5;
  try {
    p.validate();
    FAIL() << "no throw";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("band_in_epsilons"), std::string::npos);
  }
}

}  // namespace
}  // namespace pointsurf
