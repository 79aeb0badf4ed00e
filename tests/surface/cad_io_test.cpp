// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/surface/cad_io.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <unistd.h>

#include "pointsurf/core/error.h"
#include "pointsurf/surface/fit_bspline.h"
#include "support/bspline_shapes.h"
#include "support/files.h"

// STEP and IGES written by write_cad and read back by OpenCASCADE (read_cad): the same degrees,
// knots and control points, in the declared unit, far from the origin too.
namespace pointsurf {
namespace {

using Eigen::Vector3d;
namespace fs = std::filesystem;

fs::path scratch(const std::string& name) { return fs::temp_directory_path() / ("pointsurf_cad_" + std::to_string(::getpid()) + "_" + name); }

// A bicubic x quadratic surface with uneven interior knots (one double) and a wavy net.
BSplineSurface wavy_cad_surface(const Vector3d& origin = Vector3d::Zero()) { return test::wavy_bspline(2, origin, 11); }

void expect_same_surface(const BSplineSurface& a, const BSplineSurface& b, double tolerance) {
  ASSERT_EQ(a.degree_u(), b.degree_u());
  ASSERT_EQ(a.degree_v(), b.degree_v());
  ASSERT_EQ(a.count_u(), b.count_u());
  ASSERT_EQ(a.count_v(), b.count_v());
  ASSERT_EQ(a.knots_u().size(), b.knots_u().size());
  ASSERT_EQ(a.knots_v().size(), b.knots_v().size());
  for (std::size_t k = 0; k < a.knots_u().size(); ++k) EXPECT_NEAR(a.knots_u()[k], b.knots_u()[k], 1e-12);
  for (std::size_t k = 0; k < a.knots_v().size(); ++k) EXPECT_NEAR(a.knots_v()[k], b.knots_v()[k], 1e-12);
  double worst = 0.0;
  for (int i = 0; i < a.count_u(); ++i)
    for (int j = 0; j < a.count_v(); ++j) worst = std::max(worst, ((a.origin() + a.control(i, j)) - (b.origin() + b.control(i, j))).norm());
  EXPECT_LT(worst, tolerance);
  for (double u = 0.05; u < 1.0; u += 0.3)
    for (double v = 0.05; v < 1.0; v += 0.3) EXPECT_LT((a.point(u, v) - b.point(u, v)).norm(), tolerance);
}

TEST(CadIo, StepAndIgesKeepControlPointsKnotsAndDegrees) {
  const std::vector<BSplineSurface> surfaces = {wavy_cad_surface(), wavy_cad_surface(Vector3d(5.0, 0.0, 1.0))};
  for (const char* name : {"two.step", "two.igs"}) {
    SCOPED_TRACE(name);
    const fs::path file = scratch(name);
    write_cad(file, surfaces);
    const CadSurfaces back = read_cad(file);
    EXPECT_EQ(back.faces, 2u);
    EXPECT_EQ(back.skipped, 0u);
    ASSERT_EQ(back.surfaces.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) expect_same_surface(surfaces[k], back.surfaces[k], 1e-9);
    fs::remove(file);
  }
}

// The file declares the unit the coordinates are in: read back in metres, a surface written in
// millimetres is a thousand times smaller; in millimetres it is as written.
TEST(CadIo, TheUnitIsDeclaredAndConvertedOnReading) {
  const BSplineSurface s = wavy_cad_surface();
  for (const char* name : {"mm.stp", "mm.iges"}) {
    SCOPED_TRACE(name);
    const fs::path file = scratch(name);
    write_cad(file, std::vector<BSplineSurface>{s}, {LengthUnit::Millimetre});
    const CadSurfaces mm = read_cad(file, LengthUnit::Millimetre);
    ASSERT_EQ(mm.surfaces.size(), 1u);
    expect_same_surface(s, mm.surfaces[0], 1e-9);
    const CadSurfaces m = read_cad(file, LengthUnit::Metre);
    ASSERT_EQ(m.surfaces.size(), 1u);
    EXPECT_NEAR((m.surfaces[0].point(0.3, 0.4) - 0.001 * s.point(0.3, 0.4)).norm(), 0.0, 1e-12);
    fs::remove(file);
  }
  EXPECT_EQ(parse_length_unit("Millimetre"), LengthUnit::Millimetre);
  EXPECT_EQ(parse_length_unit("in"), LengthUnit::Inch);
  EXPECT_DOUBLE_EQ(metres_per(LengthUnit::Inch), 0.0254);
  test::expect_error<UsageError>([] { parse_length_unit("furlong"); }, "choose m, mm or in");
}

// Georeferenced coordinates (1e6 m east, 5e6 m north) keep sub-millimetre positions.
TEST(CadIo, FarFromTheOriginKeepsSubMillimetrePrecision) {
  const BSplineSurface s = wavy_cad_surface(Vector3d(6.5e5, 5.3e6, 120.0));
  const fs::path file = scratch("far.step");
  write_cad(file, std::vector<BSplineSurface>{s});
  const CadSurfaces back = read_cad(file);
  ASSERT_EQ(back.surfaces.size(), 1u);
  expect_same_surface(s, back.surfaces[0], 1e-6);
  fs::remove(file);
}

// A fitted surface goes through the file unchanged: the fit's deviation stays the file's.
TEST(CadIo, AFittedSurfaceSurvivesTheRoundTrip) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<Vector3d> points;
  for (int k = 0; k < 4000; ++k) {
    const double x = uni(rng), y = uni(rng);
    points.emplace_back(x, y, 0.2 * std::sin(3.0 * x) * std::cos(2.0 * y));
  }
  const BSplineFitResult fit = fit_bspline_surface(points);
  const fs::path file = scratch("fit.igs");
  write_cad(file, std::vector<BSplineSurface>{fit.surface});
  const CadSurfaces back = read_cad(file);
  ASSERT_EQ(back.surfaces.size(), 1u);
  expect_same_surface(fit.surface, back.surfaces[0], 1e-9);
  fs::remove(file);
}

TEST(CadIo, BadRequestsNameTheProblemAndLeaveNoFile) {
  const BSplineSurface s = wavy_cad_surface();
  test::expect_error<UsageError>([&] { write_cad(scratch("x.ply"), std::vector<BSplineSurface>{s}); }, "use .step, .stp, .igs or .iges");
  test::expect_error<UsageError>([&] { write_cad(scratch("none.step"), std::vector<BSplineSurface>{}); }, "no surfaces");
  test::expect_error<UsageError>([&] { write_cad(scratch("empty.step"), std::vector<BSplineSurface>{BSplineSurface{}}); }, "surface 0 is empty");
  EXPECT_FALSE(fs::exists(scratch("empty.step")));
  EXPECT_THROW(write_cad(fs::path("/nonexistent-dir/x.step"), std::vector<BSplineSurface>{s}), Error);
  EXPECT_THROW(read_cad(scratch("missing.step")), InputError);
  const fs::path junk = scratch("junk.step");
  std::ofstream(junk) << "this is not STEP\n";
  EXPECT_THROW(read_cad(junk), InputError);
  fs::remove(junk);
}

}  // namespace
}  // namespace pointsurf
