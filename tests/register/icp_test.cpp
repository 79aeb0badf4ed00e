// SPDX-License-Identifier: GPL-3.0-or-later
// ICP: known rigid transforms recovered from a near start with 70 % overlap and noise (point and
// plane), the same relative pose 1e6 m away, invariance under permutation, the normal-angle
// rejection on a thin wall seen from one side, identical clouds, no overlap, too few points,
// evaluate_registration against known distances, progress and cancelling, and every error path.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "pointsurf/core/error.h"
#include "pointsurf/register/icp.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/scan_views.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

RigidTransform random_motion(std::mt19937_64& rng, double max_angle_deg, double max_translation) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  const Eigen::Vector3d t = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized() * (max_translation * u(rng));
  return RigidTransform(Eigen::AngleAxisd(max_angle_deg * u(rng) * std::numbers::pi / 180.0, axis).toRotationMatrix(), t);
}

// A motion of exactly `angle_deg` and `translation` length, about `center`.
RigidTransform exact_motion(std::mt19937_64& rng, double angle_deg, double translation, const Eigen::Vector3d& center) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  const Eigen::Vector3d t = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized() * translation;
  return RigidTransform::about(center, Eigen::AngleAxisd(angle_deg * std::numbers::pi / 180.0, axis).toRotationMatrix(), t);
}


// A closed, smooth, asymmetric surface: a sphere of radius 1 with bumps, r(u) = 1 + b(u) for
// unit directions u, sampled at `n` seeded random directions, normals from the gradient of
// |x| - 1 - b(x / |x|) by central differences.
double bump(const Eigen::Vector3d& u) {
  return 0.3 * u.x() * u.y() + 0.25 * u.z() * u.z() * u.z() + 0.1 * u.x() + 0.08 * std::sin(9.0 * u.x() + 4.0 * u.y()) * std::cos(7.0 * u.z());
}
double implicit(const Eigen::Vector3d& x) { return x.norm() - 1.0 - bump(x.normalized()); }

PointCloud sample_bumpy(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d u = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    const Eigen::Vector3d x = (1.0 + bump(u)) * u;
    Eigen::Vector3d grad;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d h = Eigen::Vector3d::Unit(a) * 1e-6;
      grad[a] = (implicit(x + h) - implicit(x - h)) / 2e-6;
    }
    c.positions.push_back(x);
    c.normals.push_back(grad.normalized());
  }
  return c;
}

// Two partial scans of the bumpy sphere, sampled independently: the target keeps the first 77 %
// of its points along a direction, the source the last 77 % of its own, so 70 % of the source
// lies over the target. The source is noisy and moved by `truth.inverse()`, so `truth` maps it
// back onto the target.
struct Pair {
  PointCloud source, target;
  RigidTransform truth;
  double spacing = 0.0;   // the source's mean spacing
};

PointCloud keep_along(const PointCloud& c, const Eigen::Vector3d& dir, double from, double to) {
  std::vector<std::size_t> rank(c.size());
  std::iota(rank.begin(), rank.end(), std::size_t{0});
  std::sort(rank.begin(), rank.end(), [&](std::size_t a, std::size_t b) { return c.positions[a].dot(dir) < c.positions[b].dot(dir); });
  return c.select(std::vector<std::size_t>(rank.begin() + std::ptrdiff_t(from * double(c.size())), rank.begin() + std::ptrdiff_t(to * double(c.size()))));
}

Pair bumpy_pair(const RigidTransform& truth, double noise_in_spacings, std::uint64_t seed) {
  const Eigen::Vector3d dir = Eigen::Vector3d(1.0, 0.3, -0.2).normalized();
  Pair p;
  p.target = keep_along(sample_bumpy(20000, seed), dir, 0.0, 0.77);
  p.source = keep_along(sample_bumpy(20000, seed + 1000), dir, 0.23, 1.0);
  p.spacing = mean_spacing(p.source.positions);
  test::add_noise(p.source, noise_in_spacings * p.spacing, seed);
  p.truth = truth;
  truth.inverse().apply(p.source);
  return p;
}

class IcpKnownMotion : public ::testing::TestWithParam<IcpMetric> {};

TEST_P(IcpKnownMotion, RecoversSeededMotionsFromANearStartWith70PercentOverlapAndNoise) {
  std::mt19937_64 rng(2026);
  for (int trial = 0; trial < 10; ++trial) {
    const RigidTransform truth = trial == 0 ? RigidTransform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.08, -0.04, 0.12))  // pure translation
                                            : random_motion(rng, 30.0, 0.2);
    const Pair p = bumpy_pair(truth, 0.1, 100 + static_cast<std::uint64_t>(trial));
    const Eigen::Vector3d at = test::centroid(p.source);
    // The start: the truth spoiled by 3 degrees and one spacing about the source's centroid.
    const RigidTransform start = p.truth * exact_motion(rng, 3.0, p.spacing, at);
    const KdTree tree(p.target.positions);
    IcpParams params;
    params.metric = GetParam();
    params.max_iterations = 200;  // point-to-point slides slowly along a smooth surface: 40-100 here
    const RegistrationResult r = icp(p.source, p.target, tree, start, params);
    SCOPED_TRACE(::testing::Message() << "trial " << trial << ": " << r.message);
    EXPECT_TRUE(r.converged);
    EXPECT_LT(RigidTransform::rotation_error_degrees(r.transform, p.truth), 0.5);
    EXPECT_LT(RigidTransform::translation_error(r.transform, p.truth, at), 0.5 * p.spacing);
    EXPECT_GT(RigidTransform::rotation_error_degrees(start, p.truth), 2.9);  // the start was off
    EXPECT_GT(r.fitness, 0.68);
    EXPECT_LT(r.inlier_rmse, 1.5 * p.spacing);
    EXPECT_GE(r.iterations, 1u);
    EXPECT_LE(r.iterations, params.max_iterations);
  }
}

INSTANTIATE_TEST_SUITE_P(Metrics, IcpKnownMotion, ::testing::Values(IcpMetric::PointToPoint, IcpMetric::PointToPlane),
                         [](const ::testing::TestParamInfo<IcpMetric>& info) { return std::string(icp_metric_name(info.param)); });

TEST(Icp, AShiftOf1e6MetresGivesTheSameRelativePose) {
  std::mt19937_64 rng(5);
  const Pair p = bumpy_pair(random_motion(rng, 20.0, 0.2), 0.1, 9);
  const RigidTransform start = p.truth * exact_motion(rng, 2.0, p.spacing, test::centroid(p.source));
  const Eigen::Vector3d shift(1.0e6, -2.0e6, 5.0e5);
  for (IcpMetric metric : {IcpMetric::PointToPoint, IcpMetric::PointToPlane}) {
    IcpParams params;
    params.metric = metric;
    params.max_iterations = 200;
    const KdTree tree(p.target.positions);
    const RegistrationResult near = icp(p.source, p.target, tree, start, params);

    Pair far = p;
    for (Eigen::Vector3d& x : far.source.positions) x += shift;
    for (Eigen::Vector3d& x : far.target.positions) x += shift;
    // The same start seen from the shifted frame: x -> start(x - shift) + shift.
    const RigidTransform to_far(Eigen::Matrix3d::Identity(), shift), from_far(Eigen::Matrix3d::Identity(), -shift);
    const RigidTransform far_start = to_far * start * from_far;
    const KdTree far_tree(far.target.positions);
    const RegistrationResult r = icp(far.source, far.target, far_tree, far_start, params);
    ASSERT_TRUE(near.converged) << near.message;
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_EQ(r.iterations, near.iterations);
    EXPECT_LT(RigidTransform::rotation_error_degrees(r.transform, near.transform), 1e-6);
    const Eigen::Vector3d at = test::centroid(p.source);
    EXPECT_LT((r.transform.apply(at + shift) - shift - near.transform.apply(at)).norm(), 1e-6 * p.spacing);
    EXPECT_NEAR(r.inlier_rmse, near.inlier_rmse, 1e-6 * p.spacing);
    EXPECT_DOUBLE_EQ(r.fitness, near.fitness);
  }
}

TEST(Icp, DoesNotDependOnThePointOrder) {
  std::mt19937_64 rng(11);
  const Pair p = bumpy_pair(random_motion(rng, 20.0, 0.2), 0.1, 12);
  const RigidTransform start = p.truth * exact_motion(rng, 3.0, p.spacing, test::centroid(p.source));
  auto shuffled = [&](const PointCloud& c, std::uint64_t seed) {
    std::vector<std::size_t> order(c.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::shuffle(order.begin(), order.end(), std::mt19937_64(seed));
    return c.select(order);
  };
  const PointCloud source = shuffled(p.source, 1), target = shuffled(p.target, 2);
  for (IcpMetric metric : {IcpMetric::PointToPoint, IcpMetric::PointToPlane}) {
    IcpParams params;
    params.metric = metric;
    const KdTree tree(p.target.positions), shuffled_tree(target.positions);
    const RegistrationResult a = icp(p.source, p.target, tree, start, params);
    const RegistrationResult b = icp(source, target, shuffled_tree, start, params);
    EXPECT_EQ(a.iterations, b.iterations);
    EXPECT_EQ(a.correspondences, b.correspondences);
    EXPECT_DOUBLE_EQ(a.fitness, b.fitness);
    EXPECT_LT(RigidTransform::rotation_error_degrees(a.transform, b.transform), 1e-9);
    EXPECT_LT(RigidTransform::translation_error(a.transform, b.transform, test::centroid(p.source)), 1e-9 * p.spacing);
  }
}

// Fixed blocks summed in order: one thread gives the very same answer as all of them.
TEST(Icp, OneThreadGivesTheSameAnswerAsMany) {
  std::mt19937_64 rng(13);
  const Pair p = bumpy_pair(random_motion(rng, 20.0, 0.2), 0.1, 14);
  const RigidTransform start = p.truth * exact_motion(rng, 3.0, p.spacing, test::centroid(p.source));
  const KdTree tree(p.target.positions);
  for (IcpMetric metric : {IcpMetric::PointToPoint, IcpMetric::PointToPlane}) {
    IcpParams params;
    params.metric = metric;
    const RegistrationResult many = icp(p.source, p.target, tree, start, params);
    RegistrationResult one;
    {
      const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
      one = icp(p.source, p.target, tree, start, params);
    }
    EXPECT_EQ(one.iterations, many.iterations);
    EXPECT_EQ(one.correspondences, many.correspondences);
    EXPECT_EQ(one.inlier_rmse, many.inlier_rmse);
    EXPECT_EQ(one.transform.matrix(), many.transform.matrix());
  }
}

// A hollow box (outer half-size 1, wall 0.1 thick) scanned all round is the target: outer faces
// with outward normals, inner faces with normals towards the centre (out of the material). The
// source sees the three outer faces towards (1, 1, 1), and starts 0.07 too far in on each: the
// inner faces are nearer (0.03) than the right ones (0.07). Plain ICP locks onto the inner faces;
// with the normal check the inner faces face the other way and the outer ones are paired.
struct HollowBox {
  PointCloud source, target;
  RigidTransform truth, start;
};

HollowBox hollow_box() {
  constexpr double wall = 0.1;
  HollowBox b;
  b.target = test::sample_cube(24000, 1.0, 1);
  PointCloud inner = test::sample_cube(21000, 1.0 - wall, 2);
  for (Eigen::Vector3d& n : inner.normals) n = -n;
  b.target.append(inner);
  const PointCloud outer = test::sample_cube(24000, 1.0, 3);
  std::vector<std::size_t> seen;
  for (std::size_t i = 0; i < outer.size(); ++i)
    if (outer.normals[i].dot(Eigen::Vector3d(1.0, 1.0, 1.0)) > 0.0) seen.push_back(i);
  b.source = outer.select(seen);
  test::add_noise(b.source, 0.002, 4);
  std::mt19937_64 rng(7);
  b.truth = exact_motion(rng, 10.0, 0.2, Eigen::Vector3d::Zero());
  b.truth.inverse().apply(b.source);
  // 0.07 inwards along each of the three axes, after the truth.
  b.start = RigidTransform(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Constant(-0.7 * wall)) * b.truth;
  return b;
}

TEST(Icp, TheNormalAngleCheckKeepsAThinWallFromLockingOntoItsFarSide) {
  const HollowBox b = hollow_box();
  const KdTree tree(b.target.positions);
  for (IcpMetric metric : {IcpMetric::PointToPoint, IcpMetric::PointToPlane}) {
    IcpParams params;
    params.metric = metric;
    params.max_distance = Length::cloud(0.15);
    params.max_normal_deg = 180.0;
    const RegistrationResult plain = icp(b.source, b.target, tree, b.start, params);
    params.max_normal_deg = 45.0;
    const RegistrationResult checked = icp(b.source, b.target, tree, b.start, params);
    SCOPED_TRACE(icp_metric_name(metric));
    const Eigen::Vector3d at = Eigen::Vector3d::Zero();
    const double plain_error = RigidTransform::translation_error(plain.transform, b.truth, at);
    const double checked_error = RigidTransform::translation_error(checked.transform, b.truth, at);
    EXPECT_GT(plain_error, 0.08) << plain.message;    // on the inner faces: 0.1 along each axis
    EXPECT_LT(checked_error, 0.005) << checked.message;
    EXPECT_LT(RigidTransform::rotation_error_degrees(checked.transform, b.truth), 0.2);
    EXPECT_TRUE(checked.converged) << checked.message;
  }
}

TEST(Icp, IdenticalCloudsConvergeAtOnceWithZeroRmse) {
  const PointCloud cloud = test::sample_cube(3000, 1.0, 5);
  const KdTree tree(cloud.positions);
  for (IcpMetric metric : {IcpMetric::PointToPoint, IcpMetric::PointToPlane}) {
    IcpParams params;
    params.metric = metric;
    const RegistrationResult r = icp(cloud, cloud, tree, RigidTransform(), params);
    EXPECT_TRUE(r.converged) << r.message;
    EXPECT_LE(r.iterations, 1u);
    EXPECT_EQ(r.iterations, 0u);
    EXPECT_LT(r.inlier_rmse, 1e-12);
    EXPECT_DOUBLE_EQ(r.fitness, 1.0);
    EXPECT_EQ(r.correspondences, cloud.size());
    EXPECT_LT(r.transform.angle_degrees(), 1e-12);
    EXPECT_LT(r.transform.translation().norm(), 1e-12);
  }
}

TEST(Icp, NoOverlapOrTooFewPointsIsAnAnswerNotAnException) {
  const PointCloud target = sample_bumpy(2000, 1);
  const KdTree tree(target.positions);
  PointCloud far = sample_bumpy(2000, 2);
  for (Eigen::Vector3d& x : far.positions) x.x() += 10.0;
  for (IcpMetric metric : {IcpMetric::PointToPoint, IcpMetric::PointToPlane}) {
    IcpParams params;
    params.metric = metric;
    const RegistrationResult r = icp(far, target, tree, RigidTransform(), params);
    EXPECT_FALSE(r.converged);
    EXPECT_NE(r.message.find("too few pairs (0;"), std::string::npos) << r.message;
    EXPECT_EQ(r.iterations, 0u);
    EXPECT_DOUBLE_EQ(r.fitness, 0.0);

    PointCloud two = target.select(std::vector<std::size_t>{0, 1});
    const RegistrationResult few = icp(two, target, tree, RigidTransform(), params);
    EXPECT_FALSE(few.converged);
    EXPECT_NE(few.message.find("too few source points (2;"), std::string::npos) << few.message;

    params.max_normal_deg = 180.0;  // an empty cloud has no normals to check
    const RegistrationResult empty = icp(PointCloud{}, target, tree, RigidTransform(), params);
    EXPECT_FALSE(empty.converged);
  }
}

// A sphere turned about its centre fits itself at every rotation: the rotation is free, the
// centre is not. ICP must stop with the centre found, not wander or run to the cap.
TEST(Icp, ASphereTurnedAboutItsCentreStopsWithTheCentreFound) {
  const Eigen::Vector3d center(3.0, -1.0, 2.0);
  const PointCloud target = test::sample_sphere(5000, 1.0, center, 1);
  const KdTree tree(target.positions);
  PointCloud source = test::sample_sphere(5000, 1.0, center, 2);
  std::mt19937_64 rng(1);
  const RigidTransform moved = exact_motion(rng, 10.0, 0.05, center);
  moved.inverse().apply(source);
  for (IcpMetric metric : {IcpMetric::PointToPoint, IcpMetric::PointToPlane}) {
    IcpParams params;
    params.metric = metric;
    params.max_distance = Length::cloud(0.2);
    const RegistrationResult r = icp(source, target, tree, RigidTransform(), params);
    SCOPED_TRACE(icp_metric_name(metric));
    EXPECT_TRUE(r.converged) << r.message;
    EXPECT_LT(r.iterations, params.max_iterations);
    EXPECT_LT((r.transform.apply(moved.inverse().apply(center)) - center).norm(), 0.005);
    EXPECT_GT(r.fitness, 0.99);
  }
}

TEST(Icp, StopsAtTheIterationCapWithConvergedFalse) {
  std::mt19937_64 rng(3);
  const Pair p = bumpy_pair(random_motion(rng, 20.0, 0.2), 0.1, 4);
  const KdTree tree(p.target.positions);
  IcpParams params;
  params.metric = IcpMetric::PointToPoint;
  params.max_iterations = 2;
  params.relative_fitness = 0.0;
  params.relative_rmse = 0.0;
  const RegistrationResult r = icp(p.source, p.target, tree, p.truth * exact_motion(rng, 5.0, p.spacing, test::centroid(p.source)), params);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 2u);
  EXPECT_NE(r.message.find("iteration cap (2)"), std::string::npos) << r.message;
}

TEST(Icp, ReportsProgressAndCancels) {
  std::mt19937_64 rng(8);
  const Pair p = bumpy_pair(random_motion(rng, 20.0, 0.2), 0.1, 4);
  const KdTree tree(p.target.positions);
  const RigidTransform start = p.truth * exact_motion(rng, 3.0, p.spacing, test::centroid(p.source));
  std::vector<double> seen;
  const RegistrationResult r = icp(p.source, p.target, tree, start, IcpParams{}, [&](double f) {
    seen.push_back(f);
    return true;
  });
  ASSERT_EQ(seen.size(), r.iterations);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_GT(seen.front(), 0.0);
  EXPECT_LE(seen.back(), 1.0);
  EXPECT_THROW(icp(p.source, p.target, tree, start, IcpParams{}, [](double) { return false; }), CancelledError);
}

TEST(EvaluateRegistration, ScoresAKnownOffset) {
  // A 21 x 21 grid of spacing 0.1 and its copy 0.03 above: every point's nearest is the one below.
  PointCloud grid;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) grid.positions.emplace_back(0.1 * i + 1e6, 0.1 * j - 3e6, 40.0);
  const KdTree tree(grid.positions);
  const RigidTransform up(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, 0.03));
  const RegistrationResult r = evaluate_registration(grid, grid, tree, up, 0.05);
  EXPECT_DOUBLE_EQ(r.fitness, 1.0);
  EXPECT_NEAR(r.inlier_rmse, 0.03, 1e-9);
  EXPECT_EQ(r.correspondences, grid.size());
  EXPECT_TRUE(r.converged);
  const RegistrationResult none = evaluate_registration(grid, grid, tree, up, 0.02);
  EXPECT_DOUBLE_EQ(none.fitness, 0.0);
  EXPECT_DOUBLE_EQ(none.inlier_rmse, 0.0);
  // Half the grid moved 0.2 sideways off the target's edge in x: the last two columns find nothing within 0.05.
  const RigidTransform side(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.2, 0.0, 0.0));
  EXPECT_NEAR(evaluate_registration(grid, grid, tree, side, 0.05).fitness, 19.0 / 21.0, 1e-12);
  EXPECT_THROW(evaluate_registration(grid, grid, tree, up, 0.0), UsageError);
}

TEST(Icp, RejectsBadParametersAndMissingNormals) {
  const PointCloud cloud = test::sample_cube(500, 1.0, 5);
  const KdTree tree(cloud.positions);
  auto message_of = [&](const IcpParams& params, const PointCloud& source, const PointCloud& target) -> std::string {
    try {
      icp(source, target, tree, RigidTransform(), params);
    } catch (const UsageError& e) {
      return e.what();
    }
    return "no error";
  };
  IcpParams p;
  p.max_distance = Length::cloud(-1.0);
  EXPECT_EQ(message_of(p, cloud, cloud), "icp: icp_distance must be > 0, got -1");
  p = {};
  p.max_distance = Length::spacings(0.0);
  EXPECT_EQ(message_of(p, cloud, cloud), "icp: icp_distance must be > 0, got 0sp");
  p = {};
  p.max_normal_deg = 181.0;
  EXPECT_NE(message_of(p, cloud, cloud).find("max_normal_angle_deg"), std::string::npos);
  p = {};
  p.max_iterations = 0;
  EXPECT_EQ(message_of(p, cloud, cloud), "icp: iterations must be in [1, 100000], got 0");
  p.max_iterations = 100001;
  EXPECT_EQ(message_of(p, cloud, cloud), "icp: iterations must be in [1, 100000], got 100001");
  p = {};
  p.relative_rmse = -1.0;
  EXPECT_NE(message_of(p, cloud, cloud).find("relative_rmse"), std::string::npos);
  p = {};
  p.relative_fitness = std::nan("");
  EXPECT_NE(message_of(p, cloud, cloud).find("relative_fitness"), std::string::npos);

  PointCloud bare = cloud;
  bare.normals.clear();
  p = {};
  EXPECT_NE(message_of(p, cloud, bare).find("point-to-plane needs the target's normals"), std::string::npos);
  p.metric = IcpMetric::PointToPoint;
  EXPECT_NE(message_of(p, bare, cloud).find("needs both clouds' normals"), std::string::npos);
  p.max_normal_deg = 180.0;
  EXPECT_EQ(message_of(p, bare, bare), "no error");

  const KdTree other(bare.select(std::vector<std::size_t>{0, 1, 2}).positions);
  EXPECT_THROW(icp(bare, bare, other, RigidTransform(), p), UsageError);
  EXPECT_STREQ(icp_metric_name(IcpMetric::PointToPoint), "point");
  EXPECT_STREQ(icp_metric_name(IcpMetric::PointToPlane), "plane");
}

}  // namespace
}  // namespace pointsurf
