// SPDX-License-Identifier: GPL-3.0-or-later
// The pieces of the Poisson solver's level solve (reconstruct/detail/poisson_solver.h) that are
// pure functions of their inputs, each checked alone against an answer known by construction,
// and the per-level report of a small solve.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "reconstruct/detail/poisson_solver.h"

namespace pointsurf {
namespace {

TEST(PoissonSolverPhases, MergeSamplesIsTheAreaWeightedMeanOfTheSamplesThatReachTheLevel) {
  const std::vector<Eigen::Vector3d> q = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                          Eigen::Vector3d(5, 5, 5), Eigen::Vector3d(9, 9, 9)};
  const std::vector<double> area = {1.0, 3.0, 2.0, 100.0, 7.0};
  const std::vector<std::uint8_t> level_of = {5, 4, 6, 2, 5};  // the fourth stops at level 2
  Eigen::Vector3d mean;
  // samples 0..3 at level 4: weights 1, 3, 2 (the fourth does not reach it)
  EXPECT_DOUBLE_EQ(detail::merge_samples(q, area, level_of, 0, 4, 4, mean), 6.0);
  EXPECT_DOUBLE_EQ(mean.x(), 0.5);
  EXPECT_DOUBLE_EQ(mean.y(), 2.0 / 6.0);
  EXPECT_DOUBLE_EQ(mean.z(), 0.0);
  // at level 6 only the third remains
  EXPECT_DOUBLE_EQ(detail::merge_samples(q, area, level_of, 0, 4, 6, mean), 2.0);
  EXPECT_EQ(mean, Eigen::Vector3d(0, 1, 0));
  // a range that starts later: samples 3..4 at level 2
  EXPECT_DOUBLE_EQ(detail::merge_samples(q, area, level_of, 3, 5, 2, mean), 107.0);
  EXPECT_NEAR((mean - Eigen::Vector3d::Constant((500.0 + 63.0) / 107.0)).norm(), 0.0, 1e-14);
}

TEST(PoissonSolverPhases, ColourClassesSeparateCellsByThreeAlongSomeAxis) {
  std::vector<std::array<int, 3>> cells;
  for (int z = 0; z < 6; ++z)
    for (int y = 0; y < 6; ++y)
      for (int x = 0; x < 6; ++x) cells.push_back({x, y, z});
  const auto classes = detail::colour_classes(cells);
  std::set<std::uint32_t> seen;
  for (std::size_t c = 0; c < 27; ++c) {
    const auto& members = classes[c];
    EXPECT_EQ(members.size(), 8u) << "class " << c;  // 2^3 of the 6^3 cells per residue triple
    EXPECT_TRUE(std::is_sorted(members.begin(), members.end()));
    for (std::uint32_t i : members) {
      EXPECT_TRUE(seen.insert(i).second);
      const auto& a = cells[i];
      EXPECT_EQ(std::size_t(a[0] % 3 + 3 * (a[1] % 3) + 9 * (a[2] % 3)), c);
      for (std::uint32_t j : members) {
        if (j == i) continue;
        const auto& b = cells[j];
        const int apart = std::max({std::abs(a[0] - b[0]), std::abs(a[1] - b[1]), std::abs(a[2] - b[2])});
        EXPECT_GE(apart, 3);  // their 3^3 neighbourhoods share no cell
      }
    }
  }
  EXPECT_EQ(seen.size(), cells.size());
}

// A symmetric positive definite tridiagonal matrix with an uneven diagonal (2 + i, -1 off it).
void apply_tridiagonal(const std::vector<double>& v, std::vector<double>& out) {
  const std::size_t n = v.size();
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = (2.0 + double(i)) * v[i];
    if (i > 0) out[i] -= v[i - 1];
    if (i + 1 < n) out[i] -= v[i + 1];
  }
}

TEST(PoissonSolverPhases, JacobiPcgSolvesASymmetricPositiveDefiniteSystem) {
  const std::size_t n = 12;
  std::vector<double> truth(n), r(n), diag(n), x(n, 7.0);  // x is reset to 0 first
  for (std::size_t i = 0; i < n; ++i) truth[i] = std::sin(double(i) + 1.0), diag[i] = 2.0 + double(i);
  apply_tridiagonal(truth, r);
  double b_norm = 0.0;
  for (double v : r) b_norm += v * v;
  b_norm = std::sqrt(b_norm);
  // conjugate gradients are exact after n steps (up to rounding)
  const detail::PcgResult result = detail::jacobi_pcg(apply_tridiagonal, r, diag, x, int(n), 1e-13);
  EXPECT_NEAR(result.initial_residual, b_norm, 1e-14 * b_norm);
  EXPECT_LE(result.iterations, int(n));
  EXPECT_GE(result.iterations, 1);
  EXPECT_LE(result.final_residual, 1e-13 * b_norm);
  for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(x[i], truth[i], 1e-11) << i;
  // r holds the residual on return
  double r_norm = 0.0;
  for (double v : r) r_norm += v * v;
  EXPECT_DOUBLE_EQ(std::sqrt(r_norm), result.final_residual);
}

TEST(PoissonSolverPhases, JacobiPcgStopsAtTheIterationLimitAndOnAZeroRightHandSide) {
  const std::size_t n = 12;
  std::vector<double> truth(n, 1.0), r(n), diag(n), x(n);
  for (std::size_t i = 0; i < n; ++i) diag[i] = 2.0 + double(i);
  apply_tridiagonal(truth, r);
  const detail::PcgResult limited = detail::jacobi_pcg(apply_tridiagonal, r, diag, x, 2, 1e-13);
  EXPECT_EQ(limited.iterations, 2);
  EXPECT_LT(limited.final_residual, limited.initial_residual);
  std::vector<double> zero(n, 0.0);
  x.assign(n, 3.0);
  const detail::PcgResult none = detail::jacobi_pcg(apply_tridiagonal, zero, diag, x, 10, 1e-3);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_EQ(none.initial_residual, 0.0);
  for (double v : x) EXPECT_EQ(v, 0.0);
}

TEST(PoissonSolverPhases, ReportHasOneEntryPerLevelCompleteLevelsFull) {
  // a small sphere: levels 1..full_depth hold every node, (2^l)^3; each solve lowers the residual
  std::mt19937_64 rng(11);
  std::normal_distribution<double> gauss;
  std::vector<detail::PoissonSample> samples;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    samples.push_back({Eigen::Vector3d::Constant(0.5) + 0.3 * d, d});
  }
  detail::PoissonSystemParams params;
  params.depth = 5;
  params.full_depth = 3;
  params.kernel_depth = 3;
  detail::IsoLattice frame;
  frame.depth = 5;
  const detail::PoissonFunction f(samples, params, frame);
  ASSERT_EQ(f.levels().size(), 5u);
  for (int l = 1; l <= 5; ++l) {
    const detail::PoissonLevelReport& r = f.levels()[std::size_t(l - 1)];
    EXPECT_EQ(r.level, l);
    if (l <= 3) {
      EXPECT_EQ(r.nodes, std::size_t(1) << (3 * l));
    }
    EXPECT_GE(r.iterations, 1);
    EXPECT_LT(r.final_residual, r.initial_residual) << "level " << l;
  }
  // the finest level only within a cell of the samples' level-4 cells: the centre, 4.8 level-4
  // cells from every sample, has no nodes there
  EXPECT_LT(f.levels().back().nodes, std::size_t(1) << 15);
}

}  // namespace
}  // namespace pointsurf
