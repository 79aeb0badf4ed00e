// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/surface/bspline_surface.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/bspline_shapes.h"

namespace pointsurf {
namespace {

using Eigen::Vector3d;

// A bicubic surface over [0, 1]^2 with uneven interior knots (one double) and a wavy net.
BSplineSurface wavy_surface(const Vector3d& origin = Vector3d::Zero()) { return test::wavy_bspline(3, origin, 7); }

TEST(BSplineBasis, PartitionOfUnityAndDerivativesMatchFiniteDifferences) {
  const std::vector<double> U = {0, 0, 0, 0, 0.1, 0.25, 0.25, 0.6, 0.8, 1, 1, 1, 1};
  const int p = 3, n = int(U.size()) - p - 1;
  auto full = [&](double u, int k) {  // derivative k of every basis function at u
    std::vector<double> out(std::size_t(n), 0.0);
    const BSplineBasis b = bspline_basis(u, p, U);
    for (int j = 0; j <= p; ++j) out[std::size_t(b.span - p + j)] = b.d[std::size_t(k)][std::size_t(j)];
    return out;
  };
  const double h = 1e-6;
  for (double u : {0.0, 0.03, 0.1, 0.17, 0.25, 0.4, 0.59, 0.61, 0.93, 1.0}) {
    const BSplineBasis b = bspline_basis(u, p, U);
    double sum = 0.0, dsum = 0.0;
    for (int j = 0; j <= p; ++j) {
      sum += b.d[0][std::size_t(j)];
      dsum += b.d[1][std::size_t(j)];
      EXPECT_GE(b.d[0][std::size_t(j)], -1e-15);
    }
    EXPECT_NEAR(sum, 1.0, 1e-14) << "u = " << u;
    EXPECT_NEAR(dsum, 0.0, 1e-11) << "u = " << u;
    // Central differences inside a span; one-sided at the ends of the domain.
    const double a = std::max(0.0, u - h), c = std::min(1.0, u + h);
    const std::vector<double> lo0 = full(a, 0), hi0 = full(c, 0), lo1 = full(a, 1), hi1 = full(c, 1);
    const std::vector<double> d1 = full(u, 1), d2 = full(u, 2);
    const bool at_knot = u == 0.0 || u == 0.1 || u == 0.25 || u == 1.0;  // one-sided or across a jump
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(d1[std::size_t(i)], (hi0[std::size_t(i)] - lo0[std::size_t(i)]) / (c - a), at_knot ? 1e-3 : 1e-6) << "u = " << u << ", N" << i;
      if (!at_knot) {
        EXPECT_NEAR(d2[std::size_t(i)], (hi1[std::size_t(i)] - lo1[std::size_t(i)]) / (c - a), 2e-3) << "u = " << u << ", N" << i;
      }
    }
  }
}

TEST(BSplineBasis, FindSpanAtKnotsAndEnds) {
  const std::vector<double> U = {0, 0, 0, 0, 0.5, 0.5, 1, 1, 1, 1};
  EXPECT_EQ(bspline_find_span(0.0, 3, U), 3);
  EXPECT_EQ(bspline_find_span(0.49, 3, U), 3);
  EXPECT_EQ(bspline_find_span(0.5, 3, U), 5);
  EXPECT_EQ(bspline_find_span(1.0, 3, U), 5);
  EXPECT_EQ(bspline_find_span(2.0, 3, U), 5);
  EXPECT_EQ(bspline_find_span(-1.0, 3, U), 3);
}

TEST(BSplineSurface, BilinearPatchIsExact) {
  const std::vector<double> K = {0, 0, 1, 1};
  const BSplineSurface s(1, 1, K, K, 2, 2, {Vector3d(0, 0, 0), Vector3d(0, 2, 0), Vector3d(3, 0, 0), Vector3d(3, 2, 1)});
  EXPECT_LT((s.point(0.5, 0.25) - Vector3d(1.5, 0.5, 0.125)).norm(), 1e-15);
  const SurfaceDerivatives d = s.derivatives(0.5, 0.25);
  EXPECT_LT((d.su - Vector3d(3, 0, 0.25)).norm(), 1e-14);
  EXPECT_LT((d.sv - Vector3d(0, 2, 0.5)).norm(), 1e-14);
  EXPECT_LT((d.suv - Vector3d(0, 0, 1)).norm(), 1e-14);
  EXPECT_LT(d.suu.norm() + d.svv.norm(), 1e-14);
}

TEST(BSplineSurface, DerivativesMatchFiniteDifferences) {
  const BSplineSurface s = wavy_surface();
  const double h = 1e-6;
  for (double u : {0.05, 0.33, 0.5, 0.9})
    for (double v : {0.1, 0.42, 0.77}) {
      const SurfaceDerivatives d = s.derivatives(u, v);
      EXPECT_LT((d.point - s.point(u, v)).norm(), 1e-14);
      const SurfaceDerivatives du0 = s.derivatives(u - h, v), du1 = s.derivatives(u + h, v);
      const SurfaceDerivatives dv0 = s.derivatives(u, v - h), dv1 = s.derivatives(u, v + h);
      EXPECT_LT((d.su - (du1.point - du0.point) / (2 * h)).norm(), 1e-6);
      EXPECT_LT((d.sv - (dv1.point - dv0.point) / (2 * h)).norm(), 1e-6);
      EXPECT_LT((d.suu - (du1.su - du0.su) / (2 * h)).norm(), 1e-5);
      EXPECT_LT((d.svv - (dv1.sv - dv0.sv) / (2 * h)).norm(), 1e-5);
      EXPECT_LT((d.suv - (dv1.su - dv0.su) / (2 * h)).norm(), 1e-5);
      const Vector3d n = s.normal(u, v);
      EXPECT_NEAR(n.norm(), 1.0, 1e-14);
      EXPECT_NEAR(n.dot(d.su), 0.0, 1e-12);
      EXPECT_NEAR(n.dot(d.sv), 0.0, 1e-12);
    }
}

TEST(BSplineSurface, KnotInsertionLeavesTheSurfaceUnchanged) {
  BSplineSurface s = wavy_surface(Vector3d(1e6, -2e6, 300));
  const BSplineSurface before = s;
  s.insert_knot_u(0.33);
  s.insert_knot_u(0.45);  // an existing knot: multiplicity 2 -> 3
  s.insert_knot_u(0.33);
  s.insert_knot_v(0.6);
  s.insert_knot_v(0.01);
  EXPECT_EQ(s.count_u(), before.count_u() + 3);
  EXPECT_EQ(s.count_v(), before.count_v() + 2);
  EXPECT_EQ(s.knots_u().size(), before.knots_u().size() + 3);
  double worst = 0.0;
  for (int a = 0; a <= 40; ++a)
    for (int b = 0; b <= 40; ++b) {
      const double u = a / 40.0, v = b / 40.0;
      worst = std::max(worst, (s.local_point(u, v) - before.local_point(u, v)).norm());
      const SurfaceDerivatives d0 = before.derivatives(u, v), d1 = s.derivatives(u, v);
      worst = std::max(worst, (d1.su - d0.su).norm() * 1e-2);
    }
  EXPECT_LT(worst, 1e-12);
  EXPECT_THROW(s.insert_knot_u(0.45), UsageError);  // multiplicity would exceed the degree
  EXPECT_THROW(s.insert_knot_u(1.0), UsageError);
  EXPECT_THROW(s.insert_knot_v(-0.5), UsageError);
}

TEST(BSplineSurface, ClosestPointFindsAKnownFootPoint) {
  const BSplineSurface s = wavy_surface(Vector3d(5e5, 5e5, 10));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> param(0.05, 0.95), offset(-0.05, 0.05);
  for (int k = 0; k < 50; ++k) {
    const double u = param(rng), v = param(rng);
    // A point off the surface along its normal, close enough that the foot is unique.
    const Vector3d x = s.point(u, v) + offset(rng) * s.normal(u, v);
    const SurfaceFootPoint c = s.closest(x, std::clamp(u + 0.1, 0.0, 1.0), std::clamp(v - 0.1, 0.0, 1.0));
    EXPECT_TRUE(c.converged);
    EXPECT_NEAR(c.u, u, 1e-8);
    EXPECT_NEAR(c.v, v, 1e-8);
    EXPECT_NEAR(c.distance, (x - s.point(u, v)).norm(), 1e-9);
  }
  // A point beyond the border lands on it, the foot orthogonal along the border.
  const Vector3d out = s.point(1.0, 0.5) + 0.5 * s.derivatives(1.0, 0.5).su.normalized();
  const SurfaceFootPoint c = s.closest(out, 0.5, 0.5);
  EXPECT_DOUBLE_EQ(c.u, 1.0);
  EXPECT_NEAR(s.derivatives(c.u, c.v).sv.dot(c.point - out), 0.0, 1e-8);
}

TEST(BSplineSurface, ClosestPointFallsBackWhenNewtonCannotConverge) {
  const BSplineSurface s = wavy_surface();
  const Vector3d x = s.point(0.8, 0.7) + 0.01 * s.normal(0.8, 0.7);
  // One iteration cannot converge from the far corner: the grid search gives a better start.
  const SurfaceFootPoint c = s.closest(x, 0.0, 0.0, 1);
  EXPECT_TRUE(c.used_fallback);
  const SurfaceFootPoint full = s.closest(x, 0.0, 0.0);
  EXPECT_NEAR(full.distance, 0.01, 1e-9);
}

TEST(BSplineSurface, InvalidDefinitionsAreRejected) {
  const std::vector<double> K = {0, 0, 0, 0, 1, 1, 1, 1};
  const std::vector<Vector3d> net(16, Vector3d::Zero());
  EXPECT_NO_THROW(BSplineSurface(3, 3, K, K, 4, 4, net));
  EXPECT_THROW(BSplineSurface(3, 3, K, K, 4, 3, net), UsageError);
  EXPECT_THROW(BSplineSurface(0, 3, K, K, 4, 4, net), UsageError);
  EXPECT_THROW(BSplineSurface(3, 3, {0, 0, 0, 0.5, 1, 1, 1, 1}, K, 4, 4, net), UsageError);
  EXPECT_THROW(BSplineSurface(3, 3, {0, 0, 0, 0, 1, 1, 1, 0.5}, K, 4, 4, net), UsageError);
  try {
    (void)BSplineSurface(3, 3, K, K, 4, 4, std::vector<Vector3d>(15, Vector3d::Zero()));
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("15 control points given, expected 4 x 4 = 16"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)BSplineSurface().point(0, 0), UsageError);
}

}  // namespace
}  // namespace pointsurf
