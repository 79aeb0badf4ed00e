// SPDX-License-Identifier: GPL-3.0-or-later
// The phases of detect_primitives (shape/detail/primitive_detection.h), each run alone on a small
// cloud whose answer is known by construction: a square grid on the plane z = 0 with normals +z,
// a few outliers off it whose normals lie in the plane, and (where said) a small second patch of
// the same plane far from the first.
#include <algorithm>
#include <numeric>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "pointsurf/shape/primitives.h"
#include "shape/detail/primitive_detection.h"

namespace pointsurf {
namespace {

using detail::ExtractedShape;
using detail::PrimitiveCandidate;
using detail::PrimitiveDetection;

constexpr int kGrid = 40;            // grid points per side of the main patch
constexpr double kStep = 0.05;       // grid spacing
constexpr std::size_t kOutliers = 20;

struct Scene {
  PointCloud cloud;
  std::set<std::uint32_t> patch;     // input indices of the main patch
  std::set<std::uint32_t> outliers;  // input indices off the plane
};

// The main patch (kGrid x kGrid points), the outliers at z = 0.3 .. 0.49 with normals +x and,
// when `second`, a 5 x 5 patch of the same plane 5 units away.
Scene make_scene(bool second = false, bool outliers = true) {
  Scene s;
  auto add = [&](const Vector3d& p, const Vector3d& n) {
    s.cloud.positions.push_back(p);
    s.cloud.normals.push_back(n);
    return std::uint32_t(s.cloud.positions.size() - 1);
  };
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j) s.patch.insert(add({i * kStep, j * kStep, 0.0}, Vector3d::UnitZ()));
  for (std::size_t k = 0; outliers && k < kOutliers; ++k)
    s.outliers.insert(add({0.1 * double(k % 5), 0.3 * double(k / 5), 0.3 + 0.01 * double(k)}, Vector3d::UnitX()));
  for (int i = 0; second && i < 5; ++i)
    for (int j = 0; j < 5; ++j) add({5.0 + i * kStep, j * kStep, 0.0}, Vector3d::UnitZ());
  return s;
}

PrimitiveParams plane_params() {
  PrimitiveParams p;
  p.types = {PrimitiveType::Plane};
  p.epsilon = Length::cloud(0.01);
  p.cluster_epsilon = Length::cloud(0.12);
  p.min_points = 100;
  return p;
}

// The phases before the search.
void prepare(PrimitiveDetection& x) {
  ASSERT_TRUE(x.resolve_parameters());
  x.sort_in_morton_order();
  x.draw_scoring_subsets();
  x.build_octrees();
}

Primitive plane(const Vector3d& point, const Vector3d& normal) {
  Primitive s;
  s.type = PrimitiveType::Plane;
  s.point = point;
  s.axis = normal.normalized();
  return s;
}

// Input indices of ranks.
std::set<std::uint32_t> inputs(const PrimitiveDetection& x, const std::vector<std::uint32_t>& ranks) {
  std::set<std::uint32_t> out;
  for (std::uint32_t r : ranks) out.insert(x.order[r]);
  return out;
}

TEST(DetectPrimitivesPhases, ResolveParametersDerivesMinPointsAndTheNormalBound) {
  const Scene s = make_scene();
  PrimitiveParams p = plane_params();
  p.min_points = 0;
  p.types = {PrimitiveType::Plane, PrimitiveType::Torus};
  PrimitiveDetection x(s.cloud, p);
  ASSERT_TRUE(x.resolve_parameters());
  EXPECT_EQ(x.min_points, 30u);  // max(30, 1620 / 200)
  EXPECT_EQ(x.eps, 0.01);
  EXPECT_DOUBLE_EQ(x.band, 0.03);
  EXPECT_NEAR(x.cos_max, std::cos(25.0 * M_PI / 180.0), 1e-15);
  EXPECT_EQ(x.samples, 4);  // a torus needs a fourth point

  PointCloud same;  // every point at one place: spacing 0, nothing to fit
  same.positions.assign(5, Vector3d(1, 2, 3));
  same.normals.assign(5, Vector3d::UnitZ());
  PrimitiveParams q;
  PrimitiveDetection y(same, q);
  EXPECT_FALSE(y.resolve_parameters());
}

TEST(DetectPrimitivesPhases, SortInMortonOrderIsCentredAndIndependentOfTheInputOrder) {
  Scene s = make_scene();
  s.cloud.normals[7] = Vector3d::Zero();  // an unusable normal
  PointCloud shuffled = s.cloud;
  std::vector<std::size_t> perm(s.cloud.size());
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937(5));
  for (std::size_t i = 0; i < perm.size(); ++i)
    shuffled.positions[i] = s.cloud.positions[perm[i]], shuffled.normals[i] = s.cloud.normals[perm[i]];
  const PrimitiveParams p = plane_params();
  PrimitiveDetection a(s.cloud, p), b(shuffled, p);
  for (PrimitiveDetection* x : {&a, &b}) {
    ASSERT_TRUE(x->resolve_parameters());
    x->sort_in_morton_order();
    EXPECT_TRUE(std::is_sorted(x->sorted_codes.begin(), x->sorted_codes.end()));
    std::vector<std::uint32_t> sorted = x->order;
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);  // a permutation
    EXPECT_EQ(x->centre, bounding_box(s.cloud.positions).center());
    for (std::size_t r = 0; r < x->order.size(); ++r) EXPECT_EQ(x->pts[r], x->cloud.positions[x->order[r]] - x->centre);
    EXPECT_EQ(std::count(x->usable.begin(), x->usable.end(), 0), 1);
  }
  EXPECT_EQ(a.pts, b.pts);
  EXPECT_EQ(a.nrm, b.nrm);
  EXPECT_EQ(a.order[std::size_t(std::find(a.usable.begin(), a.usable.end(), 0) - a.usable.begin())], 7u);
}

TEST(DetectPrimitivesPhases, ScoringSubsetsDoubleInSizeAndHoldEveryUsablePointOnce) {
  PointCloud c;  // 64 x 64 = 4096 points: subsets of about 512, 512, 1024, 2048
  for (int i = 0; i < 64; ++i)
    for (int j = 0; j < 64; ++j) c.positions.emplace_back(i, j, 0.0), c.normals.push_back(Vector3d::UnitZ());
  c.normals[100] = Vector3d::Zero();
  const PrimitiveParams p = plane_params();
  PrimitiveDetection x(c, p);
  ASSERT_TRUE(x.resolve_parameters());
  x.sort_in_morton_order();
  x.draw_scoring_subsets();
  ASSERT_EQ(x.subset_count, 4);
  const double expected[4] = {512, 512, 1024, 2048};
  std::size_t total = 0;
  for (int j = 0; j < 4; ++j) {
    const auto& ranks = x.subset_ranks[std::size_t(j)];
    EXPECT_NEAR(double(ranks.size()), expected[j], 0.2 * expected[j]) << "subset " << j;
    for (std::uint32_t r : ranks) EXPECT_EQ(x.subset_of[r], j);
    total += ranks.size();
  }
  EXPECT_EQ(total, 4095u);
  EXPECT_EQ(x.remaining.size(), 4095u);
  EXPECT_TRUE(std::is_sorted(x.remaining.begin(), x.remaining.end()));
  for (std::uint32_t r = 0; r < c.size(); ++r) EXPECT_EQ(x.subset_of[r] < 0, x.usable[r] == 0);

  x.build_octrees();
  EXPECT_EQ(x.evaluated[1], 0u + x.trees[0].alive());
  EXPECT_EQ(x.evaluated.back(), 4095u);
  EXPECT_EQ(x.all->alive(), 4095u);
  // The deepest level's cells are more than two cluster cells wide, the next level's would not be.
  EXPECT_GT(x.side / std::ldexp(1.0, x.levels), 2.0 * x.cluster);
  EXPECT_LE(x.side / std::ldexp(1.0, x.levels + 1), 2.0 * x.cluster);
  EXPECT_EQ(x.level_weight.size(), std::size_t(x.levels) + 1);
  EXPECT_EQ(x.level_weight[0], 0.0);
}

TEST(DetectPrimitivesPhases, DrawCandidatesOnAPlaneGivesThatPlane) {
  const Scene s = make_scene(false, false);
  const PrimitiveParams p = plane_params();
  PrimitiveDetection x(s.cloud, p);
  prepare(x);
  x.draw_candidates();
  EXPECT_EQ(x.total_draws, 32u);
  EXPECT_EQ(x.out.candidates, 32u);
  ASSERT_FALSE(x.candidates.empty());
  const std::size_t in_first = x.trees[0].alive();  // every point of subset 0 is on the plane
  for (const PrimitiveCandidate& c : x.candidates) {
    EXPECT_EQ(c.shape.type, PrimitiveType::Plane);
    EXPECT_GT(std::abs(c.shape.axis.z()), 1.0 - 1e-12);
    EXPECT_NEAR(c.shape.axis.dot(c.shape.point - x.pts[0]), 0.0, 1e-12);
    EXPECT_EQ(c.subsets, 1);
    EXPECT_EQ(c.hits.size(), in_first);
    EXPECT_GE(c.level, 1);
    EXPECT_LE(c.level, x.levels);
  }
}

TEST(DetectPrimitivesPhases, ScoreLazilyPicksThePlaneOfThePatch) {
  const Scene s = make_scene();
  const PrimitiveParams p = plane_params();
  PrimitiveDetection x(s.cloud, p);
  prepare(x);
  // In the shifted frame the patch lies at z = -centre.z; the outliers have normals +x.
  const Vector3d on_patch(0.0, 0.0, -x.centre.z());
  PrimitiveCandidate wrong, right;
  wrong.shape = plane(on_patch, Vector3d::UnitX());  // crosses the patch, normals do not fit
  right.shape = plane(on_patch, Vector3d::UnitZ());
  x.candidates = {wrong, right};
  const std::size_t best = x.score_lazily();
  ASSERT_EQ(best, 1u);
  const PrimitiveCandidate& c = x.candidates[best];
  EXPECT_LE(c.low, double(s.patch.size()) + 1e-9);
  EXPECT_GE(c.high, double(s.patch.size()) - 1e-9);
  EXPECT_LT(x.candidates[0].high, c.low);
  for (std::uint32_t r : c.hits) EXPECT_TRUE(s.patch.count(x.order[r]));
}

TEST(DetectPrimitivesPhases, ExtractPointsKeepsTheLargestComponentOfThePlane) {
  const Scene s = make_scene(true);
  const PrimitiveParams p = plane_params();
  PrimitiveDetection x(s.cloud, p);
  prepare(x);
  const ExtractedShape e = x.extract_points(plane(Vector3d(0.0, 0.0, -x.centre.z()), Vector3d::UnitZ()));
  EXPECT_EQ(inputs(x, e.points), s.patch);  // not the far patch, not the outliers
  EXPECT_EQ(e.shape.type, PrimitiveType::Plane);
  EXPECT_GT(std::abs(e.shape.axis.z()), 1.0 - 1e-12);
}

TEST(DetectPrimitivesPhases, LargestComponentJoinsTouchingCellsOnly) {
  // Cells of 1: points 0, 1 (diagonal neighbours) and 2 are one component; 3 and 4 another.
  const std::vector<Vector3d> pts = {{0.5, 0.5, 0.5}, {1.5, 1.5, 1.5}, {2.5, 1.5, 0.5}, {9.5, 0.5, 0.5}, {9.6, 0.6, 0.5}};
  EXPECT_EQ(detail::largest_component(pts, {0, 1, 2, 3, 4}, 1.0), (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(detail::largest_component(pts, {3, 0, 4}, 1.0), (std::vector<std::uint32_t>{3, 4}));
  EXPECT_EQ(detail::largest_component(pts, {0, 3}, 1.0), (std::vector<std::uint32_t>{0}));  // a tie: the first
}

TEST(DetectPrimitivesPhases, PreferPlaneReplacesAFlatSphereByThePlane) {
  const Scene s = make_scene(false, false);
  PrimitiveParams p = plane_params();
  p.types = {PrimitiveType::Plane, PrimitiveType::Sphere};
  PrimitiveDetection x(s.cloud, p);
  prepare(x);
  std::vector<std::uint32_t> all_ranks(s.cloud.size());
  std::iota(all_ranks.begin(), all_ranks.end(), 0u);
  Primitive sphere;  // a huge sphere touching the patch
  sphere.type = PrimitiveType::Sphere;
  sphere.point = Vector3d(0.0, 0.0, 1e4);
  sphere.radius = 1e4;
  ExtractedShape e{sphere, all_ranks};
  x.prefer_plane(e);
  EXPECT_EQ(e.shape.type, PrimitiveType::Plane);
  EXPECT_EQ(e.points.size(), s.cloud.size());

  p.types = {PrimitiveType::Sphere};  // no planes asked for: the sphere stays
  PrimitiveDetection y(s.cloud, p);
  prepare(y);
  ExtractedShape f{sphere, all_ranks};
  y.prefer_plane(f);
  EXPECT_EQ(f.shape.type, PrimitiveType::Sphere);
}

TEST(DetectPrimitivesPhases, DropScatteredDropsTheCandidatesOfTheSameShape) {
  const Scene s = make_scene();
  const PrimitiveParams p = plane_params();
  PrimitiveDetection x(s.cloud, p);
  prepare(x);
  std::vector<std::uint32_t> on_patch, off;
  for (std::uint32_t r = 0; r < s.cloud.size(); ++r) (s.patch.count(x.order[r]) ? on_patch : off).push_back(r);
  const Vector3d at(0.0, 0.0, -x.centre.z());
  PrimitiveCandidate chosen, twin, other;
  chosen.shape = plane(at, Vector3d::UnitZ()), chosen.hits = on_patch;
  twin.shape = plane(at + Vector3d(0, 0, 0.002), Vector3d::UnitZ()), twin.hits = on_patch;  // within epsilon
  other.shape = plane(x.pts[off[0]], Vector3d::UnitX()), other.hits = off;
  x.candidates = {twin, other};
  x.drop_scattered(chosen);
  ASSERT_EQ(x.candidates.size(), 1u);
  EXPECT_EQ(x.candidates[0].shape.axis, Vector3d::UnitX());
  ASSERT_EQ(x.failed.size(), 1u);
  EXPECT_EQ(x.failed[0].probes.size(), 9u);
  EXPECT_EQ(x.failures, 1);
}

TEST(DetectPrimitivesPhases, AssignPointsLabelsThePatchAndRemovesItsPoints) {
  const Scene s = make_scene();
  const PrimitiveParams p = plane_params();
  PrimitiveDetection x(s.cloud, p);
  prepare(x);
  x.failures = 3;
  ExtractedShape e = x.extract_points(plane(Vector3d(0.0, 0.0, -x.centre.z()), Vector3d::UnitZ()));
  ASSERT_EQ(e.points.size(), s.patch.size());
  x.assign_points(e, 2);
  EXPECT_EQ(x.failures, 0);
  EXPECT_EQ(x.level_weight[2], 2.0);
  for (std::uint32_t i = 0; i < s.cloud.size(); ++i) EXPECT_EQ(x.out.labels[i], s.patch.count(i) ? 0 : -1);
  ASSERT_EQ(x.out.primitives.size(), 1u);
  const Primitive& found = x.out.primitives[0];
  EXPECT_EQ(found.inliers, s.patch.size());
  EXPECT_LT(found.rms, 1e-12);
  EXPECT_NEAR(found.point.z(), 0.0, 1e-12);  // back in the input frame
  EXPECT_EQ(inputs(x, x.remaining), s.outliers);
  EXPECT_EQ(x.all->alive(), kOutliers);
  EXPECT_EQ(x.evaluated.back(), kOutliers);
  EXPECT_EQ(std::move(x).result().unassigned, kOutliers);
}

}  // namespace
}  // namespace pointsurf
