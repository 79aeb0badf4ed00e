// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/multi.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "support/files.h"
#include "support/scan_views.h"

namespace pointsurf {
namespace {

// Mean over scans of the distance between where the poses and the truth put the scan's points
// (RMS over its points), in kitten spacings.
double pose_error(const std::vector<RigidTransform>& poses, const test::ScanViews& s) {
  double total = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    double sum = 0.0;
    for (const Eigen::Vector3d& p : s.clouds[k].positions) sum += (poses[k].apply(p) - s.truth[k].apply(p)).squaredNorm();
    total += std::sqrt(sum / double(s.clouds[k].size()));
  }
  return total / double(poses.size()) / test::kKittenSpacing;
}

TEST(RegisterScans, GlobalRefinementBeatsTheChainAndClosesTheLoop) {
  std::size_t better = 0;
  double chain_total = 0.0, refined_total = 0.0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const test::ScanViews s = test::scan_views(4, 0.3, seed);
    RegisterScansParams p;
    p.mode = MultiMode::Chain;
    const RegisterScansResult r = register_scans(s.clouds, p);
    ASSERT_EQ(r.poses.size(), 4u);
    // The first pass is a chain of 3 links; the refinement found the loop (3, 0) at least.
    std::size_t initial = 0;
    bool loop = false;
    for (const ScanLink& l : r.links) {
      initial += l.initial;
      loop = loop || (!l.initial && ((l.source == 3 && l.target == 0) || (l.source == 0 && l.target == 3)));
    }
    EXPECT_EQ(initial, 3u);
    EXPECT_TRUE(loop) << seed;
    EXPECT_TRUE(r.graph.converged);
    EXPECT_LT(r.graph.cost, r.graph.initial_cost);
    const double chain = pose_error(r.initial_poses, s), refined = pose_error(r.poses, s);
    std::printf("seed %llu: chain %.3f spacings, refined %.3f\n", static_cast<unsigned long long>(seed), chain, refined);
    EXPECT_LT(chain, 1.0) << seed;  // every scan placed: the chain itself is good
    better += refined < chain;
    chain_total += chain;
    refined_total += refined;
  }
  EXPECT_GE(better, 2u);
  EXPECT_LT(refined_total, 0.8 * chain_total);  // 0.64 measured
}

TEST(RegisterScans, FirstModeAndNoRefinement) {
  const test::ScanViews s = test::scan_views(3, 0.2, 7, 45.0);
  RegisterScansParams p;
  p.mode = MultiMode::First;
  p.refine = false;
  p.min_overlap = 0.05;
  const RegisterScansResult r = register_scans(s.clouds, p);
  ASSERT_EQ(r.links.size(), 2u);
  EXPECT_EQ(r.links[0].target, 0u);
  EXPECT_EQ(r.links[1].target, 0u);
  EXPECT_TRUE(r.graph.poses.empty());
  EXPECT_LT(pose_error(r.poses, s), 1.0);
  EXPECT_EQ(r.poses[0].matrix(), Eigen::Matrix4d::Identity());
}

TEST(RegisterScans, MergeNumbersTheScans) {
  const test::ScanViews s = test::scan_views(3, 0.0, 3);
  const PointCloud merged = merge_scans(s.clouds, s.truth);
  ASSERT_EQ(merged.size(), s.clouds[0].size() + s.clouds[1].size() + s.clouds[2].size());
  const ScalarField* scan = merged.fields.find("scan");
  ASSERT_NE(scan, nullptr);
  EXPECT_EQ(scan->type, ScalarType::UInt16);
  EXPECT_EQ(scan->values.front(), 0.0);
  EXPECT_EQ(scan->values.back(), 2.0);
  EXPECT_EQ(scan->values[s.clouds[0].size()], 1.0);
  // Moved into one frame: each point back on the kitten.
  const std::size_t i = s.clouds[0].size() + 5;
  EXPECT_LT((merged.positions[i] - s.truth[1].apply(s.clouds[1].positions[5])).norm(), 1e-12);
  test::expect_error<UsageError>([&] { merge_scans(s.clouds, {s.truth[0]}); }, "3 scans but 1 poses");
}

TEST(RegisterScans, BadInputIsRefused) {
  const test::ScanViews s = test::scan_views(2, 0.0, 1);
  test::expect_error<UsageError>([&] { register_scans({s.clouds[0]}); }, "1 scan; give at least 2");
  PointCloud tiny;
  for (int i = 0; i < 5; ++i) tiny.positions.emplace_back(i, 0, 0);
  test::expect_error<InputError>([&] { register_scans({s.clouds[0], tiny}); }, "scan 1: 5 points; registration needs at least 10");
  // A scan far from every other cannot be placed: the answer names it.
  PointCloud far = s.clouds[1];
  for (Eigen::Vector3d& p : far.positions) p = Eigen::Vector3d(p.x(), p.y() * 0.05, p.z() * 3.0);  // a different, flattened shape
  RegisterScansParams p;
  p.pair.min_fitness = 0.9;
  test::expect_error<ComputeError>([&] { register_scans({s.clouds[0], far}, p); }, "scan 1 could not be registered to scan 0");
  RegisterScansParams bad;
  bad.min_overlap = 0.0;
  test::expect_error<UsageError>([&] { register_scans(s.clouds, bad); }, "min_overlap must be in (0, 1]");
}

}  // namespace
}  // namespace pointsurf
