// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/align.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/rigid_transform.h"
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/register/features.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/scan_views.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const double w = g(rng), x = g(rng), y = g(rng), z = g(rng);  // sequenced draws
  return Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
}

// Normals re-estimated from the (noisy) positions, on the side of the cloud's current normals.
void reestimate_normals(PointCloud& cloud) {
  NormalParams p;
  p.k = 20;
  p.keep_variation = false;
  estimate_normals(cloud, p);
}

// Two scans of the kitten with a known motion: the points split at random between them (so the
// two samplings differ), each cropped by a plane to 85 % of the shape (about 70 % of the shape
// in common), the source moved by the inverse of `truth`, Gaussian noise on both, and normals
// estimated from the noisy points.
struct ScanPair {
  PointCloud source, target;
  RigidTransform truth;  // maps the source onto the target
  double spacing = 0.0;  // the target's mean spacing
};

ScanPair make_pair(std::uint64_t seed, double noise_in_spacings = 0.1, const Vector3d& shift = Vector3d::Zero()) {
  const PointCloud& all = test::kitten();
  std::mt19937_64 rng(seed);
  const Vector3d direction = Vector3d(std::normal_distribution<double>()(rng), std::normal_distribution<double>()(rng),
                                      std::normal_distribution<double>()(rng))
                                 .normalized();
  std::vector<double> along(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) along[i] = all.positions[i].dot(direction);
  std::vector<double> sorted = along;
  std::sort(sorted.begin(), sorted.end());
  const double low = sorted[sorted.size() * 15 / 100], high = sorted[sorted.size() * 85 / 100];
  std::vector<std::size_t> source_idx, target_idx;
  std::bernoulli_distribution half(0.5);
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (half(rng)) {
      if (along[i] <= high) source_idx.push_back(i);
    } else if (along[i] >= low) {
      target_idx.push_back(i);
    }
  }
  ScanPair pair;
  pair.source = all.select(source_idx);
  pair.target = all.select(target_idx);
  const double size = bounding_box(all.positions).diagonal();
  std::uniform_real_distribution<double> u(-0.5 * size, 0.5 * size);
  const Vector3d t(u(rng), u(rng), u(rng));
  pair.truth = RigidTransform(random_rotation(rng), t);
  pair.truth.inverse().apply(pair.source);
  const RigidTransform far(Eigen::Matrix3d::Identity(), shift);
  far.apply(pair.source);
  far.apply(pair.target);
  pair.truth = far * pair.truth * far.inverse();
  const double spacing = mean_spacing(pair.target.positions);
  test::add_noise(pair.source, noise_in_spacings * spacing, seed + 1);
  test::add_noise(pair.target, noise_in_spacings * spacing, seed + 2);
  reestimate_normals(pair.source);
  reestimate_normals(pair.target);
  pair.spacing = mean_spacing(pair.target.positions);
  return pair;
}

struct Aligned {
  RegistrationResult result;
  double rotation_error_deg = 0.0;
  double translation_error = 0.0;  // where the two motions send the source's centre
};

Aligned align(const ScanPair& pair, const AlignParams& params = {}, DescriptorType type = DescriptorType::Fpfh) {
  const KdTree source_tree(pair.source.positions), target_tree(pair.target.positions);
  DescriptorParams dp;
  dp.type = type;
  const Descriptors fs = compute_descriptors(pair.source, source_tree, dp);
  const Descriptors ft = compute_descriptors(pair.target, target_tree, dp);
  Aligned a;
  a.result = align_global(pair.source, fs, pair.target, ft, target_tree, params);
  a.rotation_error_deg = RigidTransform::rotation_error_degrees(a.result.transform, pair.truth);
  a.translation_error =
      RigidTransform::translation_error(a.result.transform, pair.truth, bounding_box(pair.source.positions).center());
  return a;
}

TEST(AlignGlobal, RecoversKnownMotionsOfAPartialNoisyKitten) {
  int good = 0, converged = 0;
  double worst_good_deg = 0.0;
  std::vector<double> errors;
  for (std::uint64_t seed = 1; seed <= 50; ++seed) {
    const ScanPair pair = make_pair(seed);
    const Aligned a = align(pair);
    const bool ok = a.rotation_error_deg < 5.0 && a.translation_error < 5.0 * pair.spacing;
    errors.push_back(a.rotation_error_deg);
    if (ok) {
      ++good;
      worst_good_deg = std::max(worst_good_deg, a.rotation_error_deg);
    }
    if (a.result.converged) ++converged;
    if (!ok)
      std::printf("seed %d: %.2f degrees, %.2f spacings off; %s\n", int(seed), a.rotation_error_deg,
                  a.translation_error / pair.spacing, a.result.message.c_str());
  }
  EXPECT_GE(good, 48) << "of 50";
  std::sort(errors.begin(), errors.end());
  std::printf("rotation errors: median %.3f, 90th %.3f, 96th %.3f degrees\n", errors[25], errors[45], errors[48]);
  EXPECT_GE(converged, 48);
  std::printf("kitten pairs: %d of 50 within 5 degrees (worst of those %.2f degrees), %d converged\n", good, worst_good_deg, converged);
}


TEST(AlignGlobal, SameAnswerWhateverTheThreadCount) {
  const ScanPair pair = make_pair(7);
  const Aligned many = align(pair);
  Aligned one;
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = align(pair);
  }
  EXPECT_TRUE(many.result.converged);
  EXPECT_EQ(one.result.iterations, many.result.iterations);
  EXPECT_EQ(one.result.correspondences, many.result.correspondences);
  EXPECT_EQ(one.result.transform.matrix(), many.result.transform.matrix());
}

TEST(AlignGlobal, SamePoseAfterAFarShiftOfBothClouds) {
  const Vector3d shift(3e6, -1e6, 2e6);
  const ScanPair near = make_pair(3), far = make_pair(3, 0.1, shift);
  const Aligned a = align(near), b = align(far);
  ASSERT_TRUE(a.result.converged);
  ASSERT_TRUE(b.result.converged);
  EXPECT_LT(a.rotation_error_deg, 5.0);
  EXPECT_LT(b.rotation_error_deg, 5.0);
  // The relative pose found far away is the one found near the origin (the far frame's
  // descriptors differ at most by a float rounding of the offsets).
  EXPECT_LT(RigidTransform::rotation_error_degrees(a.result.transform, b.result.transform), 0.5);
  const RigidTransform to_far(Eigen::Matrix3d::Identity(), shift);
  const Vector3d c = bounding_box(near.source.positions).center();
  EXPECT_LT((to_far.apply(a.result.transform.apply(c)) - b.result.transform.apply(to_far.apply(c))).norm(), near.spacing);
  EXPECT_NEAR(a.result.fitness, b.result.fitness, 0.02);
}

TEST(AlignGlobal, RecoversAPureTranslationAndIdenticalClouds) {
  ScanPair pair = make_pair(5);
  pair.source = pair.target;
  pair.truth = RigidTransform();
  Aligned a = align(pair);
  EXPECT_TRUE(a.result.converged) << a.result.message;
  EXPECT_LT(a.rotation_error_deg, 0.5);
  EXPECT_GT(a.result.fitness, 0.99);
  const RigidTransform shift(Eigen::Matrix3d::Identity(), Vector3d(0.05, -0.02, 0.01));
  shift.inverse().apply(pair.source);
  pair.truth = shift;
  a = align(pair);
  EXPECT_TRUE(a.result.converged) << a.result.message;
  EXPECT_LT(a.rotation_error_deg, 0.5);
  EXPECT_LT(a.translation_error, pair.spacing);
}

TEST(AlignGlobal, DegenerateInputsAreAnAnswerNotAnError) {
  const AlignParams params;
  // Too few points: no descriptor is valid.
  PointCloud tiny;
  tiny.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  tiny.normals.assign(3, Vector3d(0, 0, 1));
  const KdTree tiny_tree(tiny.positions);
  const Descriptors tiny_features = compute_descriptors(tiny, tiny_tree, {});
  RegistrationResult r = align_global(tiny, tiny_features, tiny, tiny_features, tiny_tree, params);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.message.find("too few descriptor matches"), std::string::npos) << r.message;
  PointCloud two;
  two.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0)};
  two.normals.assign(2, Vector3d(0, 0, 1));
  const KdTree two_tree(two.positions);
  const Descriptors two_features = compute_descriptors(two, two_tree, {});
  r = align_global(two, two_features, tiny, tiny_features, tiny_tree, params);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.message.find("too few points"), std::string::npos) << r.message;

  const auto run = [&](const PointCloud& source, const PointCloud& target) {
    const KdTree source_tree(source.positions), target_tree(target.positions);
    const Descriptors fs = compute_descriptors(source, source_tree, {});
    const Descriptors ft = compute_descriptors(target, target_tree, {});
    return align_global(source, fs, target, ft, target_tree, params);
  };
  // No overlap: a sphere against the kitten.
  PointCloud ball = test::sample_sphere(2500, 0.1, Vector3d(0.3, 0.0, 0.0), 9);
  r = run(ball, test::kitten());
  EXPECT_FALSE(r.converged) << r.message;
  // Two planes: the rotation about their normal and the slide along them are free.
  PointCloud plane_a = test::sample_plane(2500, 1.0, 1), plane_b = test::sample_plane(2500, 1.0, 2);
  test::add_noise(plane_a, 0.002, 3);
  test::add_noise(plane_b, 0.002, 4);
  r = run(plane_a, plane_b);
  EXPECT_FALSE(r.converged) << r.message;
}

TEST(AlignGlobal, BadParametersAndInputsThrowUsageError) {
  const ScanPair pair = make_pair(2);
  const KdTree source_tree(pair.source.positions), target_tree(pair.target.positions);
  const Descriptors fs = compute_descriptors(pair.source, source_tree, {});
  const Descriptors ft = compute_descriptors(pair.target, target_tree, {});
  const auto expect_usage = [&](const AlignParams& p, const std::string& text, const PointCloud* source = nullptr,
                                const Descriptors* features = nullptr) {
    try {
      align_global(source ? *source : pair.source, features ? *features : fs, pair.target, ft, target_tree, p);
      ADD_FAILURE() << "no error for " << text;
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  AlignParams p;
  p.max_distance = Length::cloud(-1.0);
  expect_usage(p, "align_global: ransac_distance must be > 0, got -1");
  p = {};
  p.max_distance = Length::spacings(0.0);
  expect_usage(p, "align_global: ransac_distance must be > 0, got 0sp");
  p = {};
  p.edge_length_ratio = 1.5;
  expect_usage(p, "edge_length_ratio must be in (0, 1]");
  p = {};
  p.max_normal_deg = 0.0;
  expect_usage(p, "ransac_max_normal_angle_deg must be in (0, 180]");
  p = {};
  p.max_iterations = 0;
  expect_usage(p, "ransac_iterations must be >= 1");
  p = {};
  p.confidence = 1.0;
  expect_usage(p, "confidence must be in (0, 1)");
  PointCloud bare = pair.source;
  bare.normals.clear();
  expect_usage({}, "needs normals on both clouds", &bare);
  expect_usage({}, "source descriptors for", nullptr, &ft);
  DescriptorParams pfh;
  pfh.type = DescriptorType::Pfh;
  const Descriptors pfh_source = compute_descriptors(pair.source, source_tree, pfh);
  expect_usage({}, "source descriptors are pfh (125 values), target fpfh (33 values)", nullptr, &pfh_source);
}

TEST(AlignGlobal, ProgressReachesOneAndCancels) {
  const ScanPair pair = make_pair(4);
  const KdTree source_tree(pair.source.positions), target_tree(pair.target.positions);
  const Descriptors fs = compute_descriptors(pair.source, source_tree, {});
  const Descriptors ft = compute_descriptors(pair.target, target_tree, {});
  double last = -1.0;
  bool monotone = true;
  align_global(pair.source, fs, pair.target, ft, target_tree, {}, [&](double f) {
    monotone = monotone && f >= last;
    last = f;
    return true;
  });
  EXPECT_TRUE(monotone);
  EXPECT_EQ(last, 1.0);
  EXPECT_THROW(align_global(pair.source, fs, pair.target, ft, target_tree, {}, [](double) { return false; }), CancelledError);
}

TEST(MatchDescriptors, NearestNeighboursInDescriptorSpace) {
  // Rows 0..4 of the target are rows 4..0 of the source; an invalid row never matches.
  Descriptors a, b;
  a.dimension = b.dimension = 2;
  a.values = {0, 0, 10, 0, 20, 0, 30, 0, 40, 0, 9, 9};
  a.valid = {1, 1, 1, 1, 1, 0};
  b.values = {41, 0, 31, 0, 19, 0, 11, 0, 1, 0, 9, 9};
  b.valid = {1, 1, 1, 1, 1, 0};
  using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
  EXPECT_EQ(match_descriptors(a, b, true), (Pairs{{0, 4}, {1, 3}, {2, 2}, {3, 1}, {4, 0}}));
  // One-way keeps every source's nearest; mutual drops a target chosen by two sources unless
  // it chose back.
  a.values[2] = 1.5f;  // source 1 now nearest to target 4 as well, and nearer than source 0
  EXPECT_EQ(match_descriptors(a, b, false), (Pairs{{0, 4}, {1, 4}, {2, 2}, {3, 1}, {4, 0}}));
  EXPECT_EQ(match_descriptors(a, b, true), (Pairs{{1, 4}, {2, 2}, {3, 1}, {4, 0}}));
  b.valid.assign(6, 0);
  EXPECT_TRUE(match_descriptors(a, b, true).empty());
}

}  // namespace
}  // namespace pointsurf
