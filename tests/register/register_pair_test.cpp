// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/register_pair.h"

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/scan_views.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::kKittenSpacing;


// The truth mapping scan 1 of `s` onto scan 0.
RigidTransform truth_1_to_0(const test::ScanViews& s) { return s.truth[0].inverse() * s.truth[1]; }

void expect_recovered(const RegisterPairResult& r, const RigidTransform& truth, const PointCloud& source, const std::string& what,
                      bool converged = true) {
  EXPECT_LT(RigidTransform::rotation_error_degrees(r.result.transform, truth), 0.5) << what;
  EXPECT_LT(RigidTransform::translation_error(r.result.transform, truth, test::centroid(source)), 0.5 * kKittenSpacing) << what;
  if (converged) {
    EXPECT_TRUE(r.result.converged) << what << ": " << r.result.message;
  }
}

TEST(RegisterPair, PartialNoisyViewsFromFarApart) {
  // Views 60 degrees apart (about 2/3 overlap), noise 0.2 spacings, frames 11-46 degrees apart.
  for (std::uint64_t seed : {1, 2, 3}) {
    const test::ScanViews s = test::scan_views(2, 0.2, seed, 60.0);
    for (DescriptorType d : {DescriptorType::Fpfh, DescriptorType::Pfh}) {
      RegisterPairParams p;
      p.features.type = d;
      const RegisterPairResult r = register_pair(s.clouds[1], s.clouds[0], p);
      expect_recovered(r, truth_1_to_0(s), s.clouds[1], fmt::format("seed {} {}", seed, descriptor_type_name(d)));
      EXPECT_GT(r.result.fitness, 0.5);
      EXPECT_GT(r.source_samples, 100u);
      EXPECT_LT(r.source_samples, s.clouds[1].size());
      EXPECT_NEAR(r.voxel, p.voxel.value * r.spacing, 1e-15);
    }
  }
}

TEST(RegisterPair, IdenticalCloudsGiveTheIdentity) {
  const PointCloud& k = test::kitten();
  const RegisterPairResult r = register_pair(k, k);
  EXPECT_LT(r.result.transform.angle_degrees(), 1e-6);
  EXPECT_LT(r.result.transform.translation().norm(), 1e-9);
  EXPECT_EQ(r.result.fitness, 1.0);
  EXPECT_LT(r.result.inlier_rmse, 1e-9);
}

TEST(RegisterPair, PureTranslation) {
  const PointCloud& k = test::kitten();
  PointCloud moved = k;
  const RigidTransform shift(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.2, -0.1, 0.05));
  shift.apply(moved);
  const RegisterPairResult r = register_pair(moved, k);
  expect_recovered(r, shift.inverse(), moved, "translation");
  EXPECT_LT(r.result.transform.angle_degrees(), 0.05);
}

TEST(RegisterPair, MissingNormalsAreEstimated) {
  const test::ScanViews s = test::scan_views(2, 0.1, 4, 45.0);
  PointCloud source = s.clouds[1], target = s.clouds[0];
  source.normals.clear();
  target.normals.clear();
  const RegisterPairResult r = register_pair(source, target);
  EXPECT_TRUE(r.source_normals_estimated);
  EXPECT_TRUE(r.target_normals_estimated);
  // Estimated normals are noisier than the scans' own near the edge of each view: the answer is
  // as close (0.24 degrees measured), though the fine ICP may still be creeping at its cap.
  expect_recovered(r, truth_1_to_0(s), source, "estimated normals", false);
}

TEST(RegisterPair, SameRelativePoseOneMillionMetresAway) {
  const test::ScanViews s = test::scan_views(2, 0.2, 5, 60.0);
  const RigidTransform far(Eigen::Matrix3d::Identity(), Eigen::Vector3d(2.0e6, -1.0e6, 3.0e5));
  PointCloud a = s.clouds[1], b = s.clouds[0];
  far.apply(a);
  far.apply(b);
  const RegisterPairResult near_result = register_pair(s.clouds[1], s.clouds[0]);
  const RegisterPairResult far_result = register_pair(a, b);
  // The same relative motion: far * T_near * far^-1 == T_far.
  const RigidTransform expected = far * near_result.result.transform * far.inverse();
  EXPECT_LT(RigidTransform::rotation_error_degrees(far_result.result.transform, expected), 0.01);
  EXPECT_LT(RigidTransform::translation_error(far_result.result.transform, expected, test::centroid(a)), 0.01 * kKittenSpacing);
}

TEST(RegisterPair, SymmetricShapeEndsWithAFit) {
  // A sphere fits itself under any rotation about its centre: any of those answers is right,
  // and the run must end (bounded RANSAC, bounded ICP) with a full fit.
  const PointCloud sphere = test::sample_sphere(3000, 1.0, Eigen::Vector3d(1, 2, 3), 3);
  PointCloud turned = sphere;
  RigidTransform::about(Eigen::Vector3d(1, 2, 3), Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix(), Eigen::Vector3d(0.1, 0, 0))
      .apply(turned);
  const RegisterPairResult r = register_pair(turned, sphere);
  EXPECT_GT(r.result.fitness, 0.95);
  // The centre is what the data fix: it goes back to its place.
  EXPECT_LT((r.result.transform.apply(Eigen::Vector3d(1.1, 2, 3)) - Eigen::Vector3d(1, 2, 3)).norm(), 0.05);
}

TEST(RegisterPair, NoOverlapIsAnAnswerNotAnError) {
  const PointCloud& k = test::kitten();
  PointCloud away = test::sample_sphere(2000, 0.3, Eigen::Vector3d(50, 0, 0), 9);
  RegisterPairParams p;
  p.align.max_iterations = 2000;
  const RegisterPairResult r = register_pair(away, k, p);
  EXPECT_FALSE(r.result.converged);
  EXPECT_LT(r.result.fitness, p.min_fitness);
  EXPECT_TRUE(test::contains(r.result.message, "no overlap found")) << r.result.message;
}

TEST(RegisterPair, BadInputIsRefused) {
  const PointCloud& k = test::kitten();
  PointCloud few;
  for (int i = 0; i < 9; ++i) few.positions.emplace_back(i, 0, 0);
  test::expect_error<InputError>([&] { register_pair(few, k); }, "source: 9 points; registration needs at least 10");
  test::expect_error<InputError>([&] { register_pair(k, PointCloud{}); }, "target: 0 points");
  PointCloud same;
  same.positions.assign(20, Eigen::Vector3d(1, 1, 1));
  test::expect_error<InputError>([&] { register_pair(same, k); }, "source: all 20 points coincide");
  RegisterPairParams p;
  p.voxel = Length::spacings(-1.0);
  test::expect_error<UsageError>([&] { register_pair(k, k, p); }, "register_pair: voxel must be >= 0, got -1sp");
  p = RegisterPairParams{};
  p.min_fitness = 2.0;
  test::expect_error<UsageError>([&] { register_pair(k, k, p); }, "min_fitness must be in [0, 1]");
}

}  // namespace
}  // namespace pointsurf
