// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/surface/fit_bspline.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

using Eigen::Vector3d;

// n random points of f over [lo, hi]^2 (seeded), each moved by Gaussian noise along `normal_of`.
std::vector<Vector3d> sample(const std::function<Vector3d(double, double)>& f, const std::function<Vector3d(double, double)>& normal_of, int n,
                             double noise, unsigned seed, double lo = 0.0, double hi = 1.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vector3d> out;
  for (int k = 0; k < n; ++k) {
    const double s = lo + (hi - lo) * unit(rng), t = lo + (hi - lo) * unit(rng);
    out.push_back(f(s, t) + noise * gauss(rng) * normal_of(s, t));
  }
  return out;
}

Vector3d saddle(double s, double t) {
  const double x = 2 * s - 1, y = 2 * t - 1;
  return {x, y, x * x - y * y};
}
Vector3d saddle_normal(double s, double t) {
  const double x = 2 * s - 1, y = 2 * t - 1;
  return Vector3d(-2 * x, 2 * y, 1).normalized();
}

// The largest distance from `truth` (noise-free points) to the fitted surface.
double distance_to(const BSplineFitResult& r, const std::vector<Vector3d>& truth) {
  double worst = 0.0;
  for (const Vector3d& x : truth) {
    // Start from the plane's parameterization of x, as the fit does.
    const Vector3d d = x - r.frame.origin;
    const double u = std::clamp((d.dot(r.frame.axis_u) - r.frame.a_min) / (r.frame.a_max - r.frame.a_min), 0.0, 1.0);
    const double v = std::clamp((d.dot(r.frame.axis_v) - r.frame.b_min) / (r.frame.b_max - r.frame.b_min), 0.0, 1.0);
    worst = std::max(worst, r.surface.closest(x, u, v).distance);
  }
  return worst;
}

void expect_consistent(const BSplineFitResult& r, std::size_t n) {
  ASSERT_EQ(r.parameters.size(), n);
  ASSERT_EQ(r.deviations.size(), n);
  double worst = 0.0;
  for (double d : r.deviations) worst = std::max(worst, std::abs(d));
  EXPECT_DOUBLE_EQ(worst, r.max_deviation);
  EXPECT_EQ(r.tolerance_met, r.max_deviation <= r.tolerance);
  EXPECT_EQ(r.control_points, std::size_t(r.surface.count_u() * r.surface.count_v()));
  EXPECT_EQ(r.stop_reason, bspline_fit_stop_name(r.stop));
}

template <class F>
void expect_error(F&& f, const std::string& text) {
  try {
    f();
    FAIL() << "no InputError; expected: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

TEST(FitBSpline, KnownBicubicHeightFieldIsRecoveredWithoutSmoothing) {
  // Truth: z = sum N_i(s) N_j(t) h_ij over x in [-1, 1], y in [-0.75, 0.75], knots {0^4, 0.5,
  // 1^4}, heights even in x and y, so the least-squares plane is z = 0 with its axes along x
  // and y, and the fit's spline space (uniform spans, 8 x 6: the knot 0.5 among them) holds
  // the truth.
  const std::vector<double> K = {0, 0, 0, 0, 0.5, 1, 1, 1, 1};
  const double g[5] = {0.1, -0.2, 0.3, -0.2, 0.1}, h[5] = {-0.1, 0.15, 0.05, 0.15, -0.1};
  auto height = [&](double s, double t) {
    const BSplineBasis bs = bspline_basis(s, 3, K, 0), bt = bspline_basis(t, 3, K, 0);
    double z = 0.0;
    for (int a = 0; a <= 3; ++a)
      for (int b = 0; b <= 3; ++b) z += bs.d[0][a] * bt.d[0][b] * g[bs.span - 3 + a] * h[bt.span - 3 + b];
    return z;
  };
  std::vector<Vector3d> points;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 30; ++j) {
      const double s = i / 40.0, t = j / 30.0;
      points.emplace_back(2 * s - 1, 1.5 * t - 0.75, height(s, t));
    }
  BSplineFitParams params;
  params.smoothing = 0.0;
  params.tolerance = 1e-7;
  params.points_per_span = double(points.size()) / 48.0;  // 8 x 6 spans
  params.max_rounds = 0;
  const BSplineFitResult r = fit_bspline_surface(points, params);
  expect_consistent(r, points.size());
  EXPECT_EQ(r.surface.count_u(), 11);
  EXPECT_EQ(r.surface.count_v(), 9);
  EXPECT_EQ(r.smoothing, 0.0);
  const double diagonal = 2.5;
  EXPECT_LT(r.max_deviation, 1e-6 * diagonal);
  EXPECT_TRUE(r.tolerance_met);
  // Between the samples too.
  std::vector<Vector3d> truth;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const double s = unit(rng), t = unit(rng);
    truth.emplace_back(2 * s - 1, 1.5 * t - 0.75, height(s, t));
  }
  EXPECT_LT(distance_to(r, truth), 1e-6 * diagonal);
  std::printf("[   INFO   ] bicubic height field: max deviation %.3g, between samples %.3g (diagonal 2.5)\n", r.max_deviation,
              distance_to(r, truth));
}

TEST(FitBSpline, TiltedPlaneWithinTolerance) {
  const Vector3d o(3, -2, 1), e1 = Vector3d(1, 0.2, 0.3).normalized(), e2 = e1.cross(Vector3d(0.1, 0.3, 1)).normalized();
  const Vector3d nrm = e1.cross(e2);
  auto plane = [&](double s, double t) -> Vector3d { return o + 3 * s * e1 + 2 * t * e2; };
  const std::vector<Vector3d> points = sample(plane, [&](double, double) { return nrm; }, 2000, 1e-3, 1);
  BSplineFitParams params;
  params.tolerance = 5e-3;
  const BSplineFitResult r = fit_bspline_surface(points, params);
  expect_consistent(r, points.size());
  EXPECT_TRUE(r.tolerance_met) << r.max_deviation;
  EXPECT_EQ(r.rounds, 0);
  EXPECT_LT(std::abs(std::abs(r.frame.normal.dot(nrm)) - 1.0), 1e-5);
  EXPECT_NEAR(r.rms_deviation, 1e-3, 2e-4);
  EXPECT_LT(distance_to(r, sample(plane, [&](double, double) { return nrm; }, 300, 0.0, 2, 0.02, 0.98)), 1.5e-3);
}

TEST(FitBSpline, QuarterCylinderWithinTolerance) {
  auto cylinder = [](double s, double t) -> Vector3d {
    const double a = 0.5 * std::numbers::pi * s;
    return {std::cos(a), 2 * t, std::sin(a)};
  };
  auto radial = [](double s, double) -> Vector3d {
    const double a = 0.5 * std::numbers::pi * s;
    return {std::cos(a), 0, std::sin(a)};
  };
  const std::vector<Vector3d> points = sample(cylinder, radial, 3000, 5e-4, 4);
  BSplineFitParams params;
  params.tolerance = 3e-3;
  const BSplineFitResult r = fit_bspline_surface(points, params);
  expect_consistent(r, points.size());
  EXPECT_TRUE(r.tolerance_met) << r.max_deviation << " after " << r.rounds << " rounds";
  EXPECT_LT(distance_to(r, sample(cylinder, radial, 300, 0.0, 5, 0.02, 0.98)), 3e-3);
  std::printf("[   INFO   ] quarter cylinder (noise 5e-4): max deviation %.3g, rms %.3g, %d rounds, %dx%d control points\n",
              r.max_deviation, r.rms_deviation, r.rounds, r.surface.count_u(), r.surface.count_v());
}

TEST(FitBSpline, NoisySaddleMeetsTheDerivedTolerance) {
  const std::vector<Vector3d> points = sample(saddle, saddle_normal, 4000, 1e-3, 6);
  const BSplineFitResult r = fit_bspline_surface(points, {});
  expect_consistent(r, points.size());
  // The tolerance derived from the noise estimate (about 1e-3): 6 x it for 4000 points.
  EXPECT_GT(r.noise, 0.5e-3);
  EXPECT_LT(r.noise, 2e-3);
  EXPECT_TRUE(r.tolerance_met) << r.max_deviation << " > " << r.tolerance << " after " << r.rounds << " rounds";
  EXPECT_LT(distance_to(r, sample(saddle, saddle_normal, 300, 0.0, 7, 0.02, 0.98)), r.tolerance);
  std::printf("[   INFO   ] saddle (noise 1e-3): tolerance %.3g, max deviation %.3g, rms %.3g, %d rounds, %dx%d control points\n",
              r.tolerance, r.max_deviation, r.rms_deviation, r.rounds, r.surface.count_u(), r.surface.count_v());
}

TEST(FitBSpline, NoiseFreeWavesAreRefinedToATightTolerance) {
  // Not a polynomial: the coarse first net cannot hold it, knot insertion must.
  auto waves = [](double s, double t) -> Vector3d {
    const double x = 2 * s - 1, y = 2 * t - 1;
    return {x, y, 0.2 * std::sin(3 * x) * std::cos(2 * y)};
  };
  const std::vector<Vector3d> points = sample(waves, [](double, double) { return Vector3d::UnitZ(); }, 3000, 0.0, 8);
  BSplineFitParams params;
  params.tolerance = 1e-4;
  params.smoothing = 1e-12;
  params.points_per_span = 500;  // a coarse first net (2 x 3 spans)
  const BSplineFitResult r = fit_bspline_surface(points, params);
  expect_consistent(r, points.size());
  EXPECT_TRUE(r.tolerance_met) << r.max_deviation << " after " << r.rounds << " rounds";
  EXPECT_GE(r.rounds, 1);
  EXPECT_LT(distance_to(r, sample(waves, [](double, double) { return Vector3d::UnitZ(); }, 300, 0.0, 9, 0.02, 0.98)), 2e-4);
  std::printf("[   INFO   ] noise-free waves, tolerance 1e-4: max deviation %.3g after %d rounds, %dx%d control points\n", r.max_deviation,
              r.rounds, r.surface.count_u(), r.surface.count_v());
}

TEST(FitBSpline, ShiftByAMillionMetresGivesTheSameDeviations) {
  const std::vector<Vector3d> points = sample(saddle, saddle_normal, 1500, 1e-3, 9);
  const Vector3d shift(1e6, -2e6, 3e5);
  std::vector<Vector3d> shifted;
  for (const Vector3d& x : points) shifted.push_back(x + shift);
  const BSplineFitResult a = fit_bspline_surface(points, {});
  const BSplineFitResult b = fit_bspline_surface(shifted, {});
  const double diagonal = 2.0 * std::sqrt(3.0);
  ASSERT_EQ(a.rounds, b.rounds);
  ASSERT_EQ(a.control_points, b.control_points);
  EXPECT_NEAR(a.max_deviation, b.max_deviation, 1e-9 * diagonal);
  EXPECT_NEAR(a.tolerance, b.tolerance, 1e-9 * diagonal);
  for (std::size_t k = 0; k < points.size(); ++k) EXPECT_NEAR(a.deviations[k], b.deviations[k], 1e-9 * diagonal) << k;
  for (double u : {0.0, 0.3, 0.71, 1.0})
    for (double v : {0.0, 0.5, 0.9}) EXPECT_LT((b.surface.point(u, v) - shift - a.surface.point(u, v)).norm(), 1e-9 * diagonal);
}

TEST(FitBSpline, PermutingThePointsChangesNothing) {
  const std::vector<Vector3d> points = sample(saddle, saddle_normal, 1500, 1e-3, 10);
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(11));
  std::vector<Vector3d> permuted;
  for (std::size_t k : order) permuted.push_back(points[k]);
  const BSplineFitResult a = fit_bspline_surface(points, {});
  const BSplineFitResult b = fit_bspline_surface(permuted, {});
  ASSERT_EQ(a.rounds, b.rounds);
  ASSERT_EQ(a.control_points, b.control_points);
  // The same up to the order of floating-point sums: within 1e-9 of the diagonal.
  const double diagonal = 2.0 * std::sqrt(3.0);
  EXPECT_NEAR(a.max_deviation, b.max_deviation, 1e-9 * diagonal);
  for (std::size_t k = 0; k < order.size(); ++k) {
    EXPECT_NEAR(b.deviations[k], a.deviations[order[k]], 1e-9 * diagonal);
    EXPECT_NEAR(b.parameters[k].x(), a.parameters[order[k]].x(), 1e-9);
  }
  for (double u : {0.0, 0.3, 1.0})
    for (double v : {0.1, 0.6}) EXPECT_LT((b.surface.point(u, v) - a.surface.point(u, v)).norm(), 1e-9 * diagonal);
}

TEST(FitBSpline, RigidMotionAndScaleMoveTheResultAlong) {
  // A rectangle (distinct principal axes, so the frame is defined by the data alone).
  auto patch = [](double s, double t) -> Vector3d {
    const double x = 2 * s - 1, y = 1.2 * t - 0.6;
    return {x, y, 0.5 * (x * x - y * y) + 0.1 * x * y * y};
  };
  const std::vector<Vector3d> points = sample(patch, [](double, double) { return Vector3d::UnitZ(); }, 2000, 1e-3, 21);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const double scale = 1000.0;
  const Vector3d shift(3e5, -4e5, 120);
  std::vector<Vector3d> moved;
  for (const Vector3d& x : points) moved.push_back(scale * (rotation * x) + shift);
  BSplineFitParams params;
  params.tolerance = 2.5e-3;  // a few rounds; the moved fit gets the same tolerance scaled
  const BSplineFitResult a = fit_bspline_surface(points, params);
  params.tolerance *= scale;
  const BSplineFitResult b = fit_bspline_surface(moved, params);
  ASSERT_EQ(a.rounds, b.rounds);
  ASSERT_EQ(a.control_points, b.control_points);
  EXPECT_GE(a.rounds, 1);
  const double diagonal = std::sqrt(4.0 + 1.44);
  for (std::size_t k = 0; k < points.size(); ++k) ASSERT_NEAR(b.deviations[k] / scale, a.deviations[k], 1e-9 * diagonal) << k;
  EXPECT_NEAR(b.noise / scale, a.noise, 1e-9 * diagonal);
  // The same surface, moved (up to the parameterization's orientation: the axes' signs come
  // from the data, so compare foot points).
  for (std::size_t k = 0; k < points.size(); k += 97) {
    const SurfaceFootPoint ca = a.surface.closest(points[k], a.parameters[k].x(), a.parameters[k].y());
    const SurfaceFootPoint cb = b.surface.closest(moved[k], b.parameters[k].x(), b.parameters[k].y());
    EXPECT_LT(((cb.point - shift) / scale - rotation * ca.point).norm(), 1e-9 * diagonal);
  }
}

TEST(FitBSpline, HeavySmoothingTendsToTheLeastSquaresPlane) {
  // The thin-plate energy vanishes exactly on planes: with a huge weight the fit is the
  // least-squares plane z = 0 of the saddle, whose rms distance is sqrt(2/5 - 2/9).
  const std::vector<Vector3d> points = sample(saddle, saddle_normal, 3000, 0.0, 22);
  BSplineFitParams params;
  params.smoothing = 1e3;
  params.max_rounds = 0;
  const BSplineFitResult r = fit_bspline_surface(points, params);
  EXPECT_NEAR(r.rms_deviation, std::sqrt(2.0 / 5.0 - 2.0 / 9.0), 0.01);
  for (double u : {0.1, 0.5, 0.9})
    for (double v : {0.2, 0.7}) {
      const SurfaceDerivatives d = r.surface.derivatives(u, v);
      EXPECT_LT(d.suu.norm() + d.suv.norm() + d.svv.norm(), 1e-3 * d.su.norm()) << u << ", " << v;
    }
  // And a weight of 1e-9 leaves the saddle itself (the border bias stays near 1e-4).
  params.smoothing = 1e-9;
  EXPECT_LT(fit_bspline_surface(points, params).max_deviation, 3e-4);
}

TEST(FitBSpline, OneThreadGivesTheSameBitsAsMany) {
  auto waves = [](double s, double t) -> Vector3d { return {s, t, 0.1 * std::sin(6 * s) * std::cos(4 * t)}; };
  const std::vector<Vector3d> points = sample(waves, [](double, double) { return Vector3d::UnitZ(); }, 3000, 1e-4, 19);
  BSplineFitParams params;
  params.points_per_span = 500;  // a few rounds of refinement
  const BSplineFitResult many = fit_bspline_surface(points, params);
  BSplineFitResult one;
  {
    tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
    one = fit_bspline_surface(points, params);
  }
  ASSERT_EQ(one.control_points, many.control_points);
  EXPECT_GE(many.rounds, 1);
  EXPECT_EQ(one.rounds, many.rounds);
  EXPECT_EQ(one.deviations, many.deviations);
  EXPECT_TRUE(one.surface.control_points() == many.surface.control_points());
}

TEST(FitBSpline, BadInputIsRefusedWithAClearInputError) {
  expect_error([] { (void)fit_bspline_surface({}); }, "fit_bspline_surface: no points");
  const std::vector<Vector3d> two = {Vector3d(0, 0, 0), Vector3d(1, 0, 0)};
  expect_error([&] { (void)fit_bspline_surface(two); }, "2 points, a surface of degree 3 needs at least (degree + 1)^2 = 16");
  std::vector<Vector3d> points = sample(saddle, saddle_normal, 200, 0.0, 12);
  points[37].y() = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { (void)fit_bspline_surface(points); }, "point 37 is not finite");
  std::vector<Vector3d> line;
  for (int k = 0; k < 50; ++k) line.emplace_back(k, 2.0 * k, -k);
  expect_error([&] { (void)fit_bspline_surface(line); }, "lie on a line");
  // A closed cylinder: its least-squares plane holds the axis; both sheets project onto it.
  const std::vector<Vector3d> cylinder = sample(
      [](double s, double t) -> Vector3d {
        const double a = 2 * std::numbers::pi * s;
        return {std::cos(a), std::sin(a), 4 * t};
      },
      [](double s, double) -> Vector3d { return {std::cos(2 * std::numbers::pi * s), std::sin(2 * std::numbers::pi * s), 0}; }, 3000, 0.0, 13);
  expect_error([&] { (void)fit_bspline_surface(cylinder); }, "folds over its base plane");
  // A hemisphere: its rim stands at 90 degrees to the plane of the equator.
  const std::vector<Vector3d> hemisphere = sample(
      [](double s, double t) -> Vector3d {
        const double z = s, a = 2 * std::numbers::pi * t, r = std::sqrt(1 - z * z);
        return {r * std::cos(a), r * std::sin(a), z};
      },
      [](double, double) -> Vector3d { return Vector3d::UnitZ(); }, 3000, 0.0, 14);
  expect_error([&] { (void)fit_bspline_surface(hemisphere); }, "folds over its base plane");
}

TEST(FitBSpline, BadParametersAreUsageErrors) {
  const std::vector<Vector3d> points = sample(saddle, saddle_normal, 200, 0.0, 15);
  BSplineFitParams params;
  params.degree = 0;
  EXPECT_THROW((void)fit_bspline_surface(points, params), UsageError);
  params = {};
  params.tolerance = -1;
  EXPECT_THROW((void)fit_bspline_surface(points, params), UsageError);
  params = {};
  params.max_control_points = 10;
  try {
    (void)fit_bspline_surface(points, params);
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("max_control_points must be >= (degree + 1)^2 = 16, got 10"), std::string::npos) << e.what();
  }
  for (const char* key : {"degree", "tolerance", "smoothing", "points_per_span", "max_rounds", "max_control_points", "parameter_corrections",
                          "max_tilt_deg"})
    EXPECT_NE(BSplineFitParams::fields().find(key), nullptr) << key;
  std::vector<std::string> reported;
  BSplineFitResult::results().record(fit_bspline_surface(points), [&](std::string key, ResultValue) { reported.push_back(key); });
  EXPECT_NE(std::find(reported.begin(), reported.end(), "max_deviation"), reported.end());
  EXPECT_NE(std::find(reported.begin(), reported.end(), "stop_reason"), reported.end());
}

TEST(FitBSpline, AToleranceThatCannotBeMetStopsAtALimitAndSaysSo) {
  const std::vector<Vector3d> points = sample(saddle, saddle_normal, 2000, 1e-3, 16);
  BSplineFitParams params;
  params.tolerance = 1e-9;
  params.max_rounds = 2;
  const BSplineFitResult r = fit_bspline_surface(points, params);
  expect_consistent(r, points.size());
  EXPECT_FALSE(r.tolerance_met);
  EXPECT_EQ(r.stop, BSplineFitStop::RoundLimit);
  EXPECT_EQ(r.stop_reason, "round limit");
  EXPECT_EQ(r.rounds, 2);
  EXPECT_GT(r.max_deviation, 1e-3);
  params.max_rounds = 50;
  params.max_control_points = 100;
  const BSplineFitResult c = fit_bspline_surface(points, params);
  expect_consistent(c, points.size());
  EXPECT_FALSE(c.tolerance_met);
  EXPECT_EQ(c.stop, BSplineFitStop::ControlPointLimit);
  EXPECT_LE(c.control_points, 100u);
  EXPECT_LT(c.rounds, 50);
}

TEST(FitBSpline, SparseDataWithoutSmoothingStaysSolvable) {
  // Points only near two opposite edges: the control points between have no data under them.
  std::vector<Vector3d> points = sample(saddle, saddle_normal, 1000, 0.0, 17);
  std::erase_if(points, [](const Vector3d& x) { return std::abs(x.x()) < 0.6; });
  BSplineFitParams params;
  params.smoothing = 0.0;
  params.points_per_span = 2;
  params.max_rounds = 0;
  const BSplineFitResult r = fit_bspline_surface(points, params);
  EXPECT_EQ(r.smoothing, 1e-12);
  for (double u = 0; u <= 1.0; u += 0.125) EXPECT_TRUE(r.surface.point(u, 0.5).allFinite());
  EXPECT_LT(r.max_deviation, 0.05);
}

TEST(FitBSpline, ProgressIsMonotoneEndsAtOneAndCancels) {
  const std::vector<Vector3d> points = sample(saddle, saddle_normal, 2000, 1e-3, 18);
  std::vector<double> seen;
  (void)fit_bspline_surface(points, {}, [&](double f) {
    seen.push_back(f);
    return true;
  });
  ASSERT_GE(seen.size(), 3u);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_GE(seen.front(), 0.0);
  EXPECT_DOUBLE_EQ(seen.back(), 1.0);
  int calls = 0;
  EXPECT_THROW((void)fit_bspline_surface(points, {}, [&](double) { return ++calls < 4; }), CancelledError);
  EXPECT_EQ(calls, 4);
}

}  // namespace
}  // namespace pointsurf
