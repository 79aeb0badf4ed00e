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
#include "shape/detail/point_octree.h"
#include "shape/detail/primitive_models.h"
#include "spatial/detail/morton.h"
#include "support/primitive_scene.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

const std::vector<PrimitiveType> kAllTypes = {PrimitiveType::Plane, PrimitiveType::Sphere, PrimitiveType::Cylinder, PrimitiveType::Cone,
                                              PrimitiveType::Torus};

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
  for (const std::vector<PrimitiveType>& types : {PrimitiveParams{}.types, kAllTypes}) {
    SCOPED_TRACE(testing::Message() << "types " << types.size());
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
  params.types = kAllTypes;
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
  params.types = PrimitiveParams{}.types;
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
  params.types = kAllTypes;
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

// One primitive of each type, with parameters in a unit-sized box.
std::vector<Primitive> one_of_each() {
  Primitive plane{PrimitiveType::Plane, Vector3d(0.1, 0.2, 0.3), Vector3d(1, 2, 3).normalized()};
  Primitive sphere{PrimitiveType::Sphere, Vector3d(0.2, -0.1, 0.0), Vector3d::UnitZ(), 0.6};
  Primitive cylinder{PrimitiveType::Cylinder, Vector3d(-0.1, 0.1, 0.2), Vector3d(0.3, -1, 0.5).normalized(), 0.4};
  Primitive cone{PrimitiveType::Cone, Vector3d(0.0, 0.3, 0.9), Vector3d(0.1, -0.2, -1).normalized(), 0.0, 35.0};
  Primitive torus{PrimitiveType::Torus, Vector3d(0.1, 0.0, -0.1), Vector3d(1, 1, 2).normalized(), 0.5};
  torus.minor_radius = 0.2;
  return {plane, sphere, cylinder, cone, torus};
}

TEST(PrimitiveModels, DistancesAreOneLipschitzAndTheOctreeCullsExactly) {
  // The octree skips a cell when the distance at its centre exceeds its radius plus the reach:
  // exact only for 1-Lipschitz distances. Checked against brute force on 20k points.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vector3d> pts(20000);
  for (Vector3d& p : pts) p = Vector3d(u(rng), u(rng), u(rng));
  std::vector<std::uint64_t> codes(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Array3d t = ((pts[i].array() + 1.0) / 2.0 * double((1 << 21) - 1)).round();
    codes[i] = detail::morton_code(std::uint64_t(t.x()), std::uint64_t(t.y()), std::uint64_t(t.z()));
  }
  std::vector<std::uint32_t> order(pts.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return codes[a] < codes[b]; });
  std::vector<Vector3d> sorted(pts.size());
  std::vector<std::uint64_t> sorted_codes(pts.size());
  for (std::size_t r = 0; r < pts.size(); ++r) sorted[r] = pts[order[r]], sorted_codes[r] = codes[order[r]];
  std::vector<std::uint32_t> ranks(pts.size()), leaf_of(pts.size());
  std::iota(ranks.begin(), ranks.end(), 0u);
  const detail::PointOctree tree(ranks, sorted, sorted_codes, 21, leaf_of);
  for (const Primitive& s : one_of_each()) {
    SCOPED_TRACE(primitive_type_name(s.type));
    auto distance = [&](const Vector3d& x) { return s.distance(x); };
    for (std::size_t i = 0; i + 1 < pts.size(); i += 2)
      ASSERT_LE(std::abs(distance(pts[i]) - distance(pts[i + 1])), (pts[i] - pts[i + 1]).norm() + 1e-12) << i;
    for (const double reach : {0.01, 0.05}) {
      std::vector<std::uint32_t> culled, brute;
      tree.visit(distance, reach, [&](const std::uint32_t* r, const std::uint32_t* end) {
        for (; r != end; ++r)
          if (distance(sorted[*r]) <= reach) culled.push_back(*r);
      });
      for (std::uint32_t r = 0; r < sorted.size(); ++r)
        if (distance(sorted[r]) <= reach) brute.push_back(r);
      EXPECT_EQ(culled, brute);
      EXPECT_FALSE(brute.empty());
    }
  }
}

TEST(PrimitiveModels, MinimalSetsOfExactPointsGiveTheirPrimitive) {
  // Points with normals sampled on each primitive; the candidates from them must hold the
  // primitive itself (a torus from 4 points, the others from the first 3).
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const Primitive& s : one_of_each()) {
    SCOPED_TRACE(primitive_type_name(s.type));
    const Vector3d x = (std::abs(s.axis.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY()).cross(s.axis).normalized(), y = s.axis.cross(x);
    int hits = 0;
    for (int trial = 0; trial < 20; ++trial) {
      Vector3d p[4], n[4];
      for (int k = 0; k < 4; ++k) {
        const double a = 2 * M_PI * u(rng), b = 2 * M_PI * u(rng), h = 0.2 + 0.6 * u(rng);
        const Vector3d radial = std::cos(a) * x + std::sin(a) * y;
        switch (s.type) {
          case PrimitiveType::Plane: p[k] = s.point + (u(rng) - 0.5) * x + (u(rng) - 0.5) * y, n[k] = s.axis; break;
          case PrimitiveType::Sphere: n[k] = std::cos(b) * radial + std::sin(b) * s.axis, p[k] = s.point + s.radius * n[k]; break;
          case PrimitiveType::Cylinder: p[k] = s.point + (h - 0.5) * s.axis + s.radius * radial, n[k] = radial; break;
          case PrimitiveType::Cone: {
            const double t = std::tan(s.angle_deg * M_PI / 180.0);
            p[k] = s.point + h * s.axis + h * t * radial;
            n[k] = (std::cos(s.angle_deg * M_PI / 180.0) * radial - std::sin(s.angle_deg * M_PI / 180.0) * s.axis).normalized();
            break;
          }
          case PrimitiveType::Torus:
            n[k] = std::cos(b) * radial + std::sin(b) * s.axis, p[k] = s.point + s.radius * radial + s.minor_radius * n[k];
            break;
        }
      }
      std::vector<Primitive> made;
      detail::make_candidates(p, n, 4, kAllPrimitives, 1e-6, std::cos(1e-3), 100.0, made);
      hits += std::any_of(made.begin(), made.end(), [&](const Primitive& m) { return m.type == s.type && matches(m, s, 1e-4); });
    }
    EXPECT_GE(hits, 18);  // a few draws are near-degenerate (e.g. a torus's 4 points on one meridian)
  }
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
  params.types = kAllTypes;
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
  p.max_normal_angle_deg = 95.0;
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.types = {};
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.epsilon = Length::cloud(-1.0);
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.probability = 1.0;
  EXPECT_THROW(p.validate(), UsageError);
  p = {};
  p.types = {PrimitiveType(7)};
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
