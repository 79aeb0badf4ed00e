// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/shape/primitives.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

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
  const PrimitiveResult r = detect_primitives(scene.cloud);
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

TEST(DetectPrimitives, DeterministicForASeed) {
  const test::PrimitiveScene scene = test::make_primitive_scene(100.0);
  EXPECT_EQ(detect_primitives(scene.cloud).labels, detect_primitives(scene.cloud).labels);
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
}

}  // namespace
}  // namespace pointsurf
