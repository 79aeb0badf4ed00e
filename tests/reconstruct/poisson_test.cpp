// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/reconstruct/poisson.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "reconstruct/detail/poisson_solver.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::expect_error;

// The solver alone: the function of a sampled unit sphere is below its iso-value inside and
// above it outside, and crosses it within 1 % of the radius along any ray.
TEST(PoissonSolver, SphereFunctionIsBelowTheIsoValueInsideAndAboveOutside) {
  const PointCloud sphere = test::sample_sphere(20000, 1.0);
  detail::IsoLattice frame;
  frame.size = 2.2;
  frame.origin = Vector3d::Constant(-1.1);
  frame.depth = 6;
  std::vector<detail::PoissonSample> samples;
  for (std::size_t i = 0; i < sphere.size(); ++i) samples.push_back({(sphere.positions[i] - frame.origin) / frame.size, sphere.normals[i]});
  detail::PoissonSystemParams params;
  params.depth = 6;
  params.kernel_depth = 4;
  const detail::PoissonFunction f(samples, params, frame);
  const double iso = f.iso_value();
  std::mt19937_64 rng(5);
  std::normal_distribution<double> gauss;
  for (int k = 0; k < 50; ++k) {
    const Vector3d dir = Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    EXPECT_LT(f.value(0.3 * dir), iso);
    EXPECT_LT(f.value(0.95 * dir), iso);
    EXPECT_GT(f.value(1.05 * dir), iso);
    EXPECT_GT(f.value(1.09 * dir), iso);
    EXPECT_GT(f.gradient(dir).dot(dir), 0.0);  // grows outwards
    double lo = 0.5, hi = 1.09;
    for (int it = 0; it < 50; ++it) (f.value(0.5 * (lo + hi) * dir) < iso ? lo : hi) = 0.5 * (lo + hi);
    EXPECT_NEAR(lo, 1.0, 0.01);
  }
  // every level solved: the residual fell
  ASSERT_EQ(f.levels().size(), 6u);
  for (const detail::PoissonLevelReport& r : f.levels()) EXPECT_LT(r.final_residual, r.initial_residual) << "level " << r.level;
  // below full_depth the octree is sparse
  EXPECT_LT(f.levels().back().nodes, std::size_t(64 * 64 * 64));
  // the samples are where the density is
  EXPECT_GT(f.density_depth(Vector3d(1, 0, 0)), 4.0);
  EXPECT_EQ(f.density_depth(Vector3d(0, 0, 0)), 0.0);
}

TEST(Poisson, SphereWithinOnePercentOfTheRadiusAtDepth7WatertightGenus0) {
  const PointCloud sphere = test::sample_sphere(20000, 1.0);
  PoissonParams params;
  params.depth = 7;
  const PoissonResult r = reconstruct_poisson(sphere, params);
  ASSERT_GT(r.mesh.vertex_count(), 1000u);
  double worst = 0.0;
  for (const Vector3d& v : r.mesh.vertices.positions) worst = std::max(worst, std::abs(v.norm() - 1.0));
  EXPECT_LT(worst, 0.01);
  EXPECT_TRUE(r.topology.watertight());
  EXPECT_EQ(r.topology.components, 1u);
  EXPECT_EQ(r.topology.non_manifold_edges, 0u);
  EXPECT_EQ(r.topology.non_manifold_vertices, 0u);
  EXPECT_EQ(r.topology.genus(), 0);
  // normals from the gradient: outward, unit
  ASSERT_EQ(r.mesh.vertices.normals.size(), r.mesh.vertex_count());
  for (std::size_t v = 0; v < r.mesh.vertex_count(); ++v) {
    EXPECT_NEAR(r.mesh.vertices.normals[v].norm(), 1.0, 1e-9);
    EXPECT_GT(r.mesh.vertices.normals[v].dot(r.mesh.vertices.positions[v].normalized()), 0.95);
  }
  // triangles counter-clockwise from outside
  for (const Triangle& t : r.mesh.triangles) {
    const Vector3d& a = r.mesh.vertices.positions[t[0]];
    EXPECT_GT((r.mesh.vertices.positions[t[1]] - a).cross(r.mesh.vertices.positions[t[2]] - a).dot(a), 0.0);
  }
  EXPECT_EQ(r.depth, 7);
  EXPECT_EQ(r.nodes_per_level.size(), 8u);
  EXPECT_GT(r.peak_bytes, 0u);
  const ScalarField* density = r.mesh.vertices.fields.find("density");
  ASSERT_NE(density, nullptr);
  for (const double d : density->values) EXPECT_GT(d, 4.0);
}

TEST(Poisson, TorusIsWatertightOfGenus1) {
  const PointCloud torus = test::sample_torus(30000, 1.0, 0.35);
  PoissonParams params;
  params.depth = 7;
  const PoissonResult r = reconstruct_poisson(torus, params);
  EXPECT_TRUE(r.topology.watertight());
  EXPECT_EQ(r.topology.components, 1u);
  EXPECT_EQ(r.topology.genus(), 1);
  for (const Vector3d& v : r.mesh.vertices.positions) {
    const double ring = std::hypot(v.x(), v.y()) - 1.0;
    EXPECT_NEAR(std::hypot(ring, v.z()), 0.35, 0.01);
  }
}

// An open surface: Poisson closes it far from the samples (here against the bounding cube),
// where the density is low; trimming at a level below the samples' density leaves the dome
// with exactly one boundary loop near its rim. The closed sphere loses nothing at that level.
TEST(Poisson, TrimmedHemisphereHasExactlyOneBoundaryLoop) {
  const PointCloud sphere = test::sample_sphere(20000, 1.0);
  std::vector<std::size_t> upper;
  for (std::size_t i = 0; i < sphere.size(); ++i)
    if (sphere.positions[i].z() >= 0.0) upper.push_back(i);
  const PointCloud dome = sphere.select(upper);
  PoissonParams params;
  params.depth = 7;
  const PoissonResult untrimmed = reconstruct_poisson(dome, params);
  double lowest = 0.0;
  for (const Vector3d& v : untrimmed.mesh.vertices.positions) lowest = std::min(lowest, v.z());
  EXPECT_LT(lowest, -0.2);  // the closing part hangs below the rim
  params.trim_depth = 5.0;  // the samples' density is about 6.1 (depth units)
  const PoissonResult r = reconstruct_poisson(dome, params);
  EXPECT_GT(r.trimmed_triangles, 0u);
  EXPECT_EQ(r.topology.boundary_loops.size(), 1u);
  EXPECT_EQ(r.topology.components, 1u);
  EXPECT_EQ(r.topology.non_manifold_edges, 0u);
  EXPECT_EQ(r.topology.non_manifold_vertices, 0u);
  for (const Vector3d& v : r.mesh.vertices.positions) {
    EXPECT_GT(v.z(), -0.2);
    if (v.z() > 0.1) {
      EXPECT_NEAR(v.norm(), 1.0, 0.01);
    }
  }
  for (const int v : r.topology.boundary_loops.front().vertices) EXPECT_NEAR(r.mesh.vertices.positions[std::size_t(v)].z(), 0.0, 0.2);
  // the closed sphere is dense everywhere: nothing goes
  PoissonParams closed;
  closed.depth = 7;
  closed.trim_depth = 5.0;
  const PoissonResult whole = reconstruct_poisson(sphere, closed);
  EXPECT_EQ(whole.trimmed_triangles, 0u);
  EXPECT_TRUE(whole.topology.watertight());
}

TEST(Poisson, DirichletBoundaryAlsoGivesTheSphere) {
  const PointCloud sphere = test::sample_sphere(10000, 1.0);
  PoissonParams params;
  params.depth = 6;
  params.boundary = PoissonBoundary::Dirichlet;
  const PoissonResult r = reconstruct_poisson(sphere, params);
  EXPECT_TRUE(r.topology.watertight());
  EXPECT_EQ(r.topology.genus(), 0);
  // the zero on the cube, 0.1 from the sphere, pulls the surface out a little
  for (const Vector3d& v : r.mesh.vertices.positions) EXPECT_NEAR(v.norm(), 1.0, 0.03);
}

// The same mesh (up to 1e-9 of the diagonal) for the points shifted by 1e6 m and shuffled, with
// linear vertex placement and with the default secant steps (the lattice is centred on the box,
// so the steps evaluate the function near the origin, not at 2e6).
TEST(Poisson, SameMeshUnderAShiftOf1e6AndAPermutation) {
  const PointCloud sphere = test::sample_sphere(6000, 1.0, Vector3d(0.1, -0.2, 0.3));
  for (const int steps : {0, 1}) {
    PoissonParams params;
    params.depth = 7;
    params.root_refinement_steps = steps;
    const PoissonResult a = reconstruct_poisson(sphere, params);
    const Vector3d shift(1e6, -2e6, 1e6);
    std::vector<std::size_t> order(sphere.size());
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), std::mt19937_64(3));
    PointCloud moved = sphere.select(order);
    for (Vector3d& p : moved.positions) p += shift;
    const PoissonResult b = reconstruct_poisson(moved, params);
    ASSERT_EQ(a.mesh.vertex_count(), b.mesh.vertex_count());
    ASSERT_EQ(a.mesh.triangle_count(), b.mesh.triangle_count());
    const double diagonal = 2.0 * std::sqrt(3.0);
    double worst = 0.0;
    for (std::size_t v = 0; v < a.mesh.vertex_count(); ++v) worst = std::max(worst, (b.mesh.vertices.positions[v] - shift - a.mesh.vertices.positions[v]).norm());
    EXPECT_LT(worst, 1e-9 * diagonal) << steps << " secant steps";
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  }
}

// Outliers off two sampled spheres (random normals, 1 % of the points in the box, as in the
// Poisson benchmark's noisy clouds) raise bubbles of low density; the default gap removes them
// and keeps both spheres.
TEST(Poisson, OutlierBubblesAreRemovedAndASecondObjectStays) {
  PointCloud cloud = test::sample_sphere(20000, 1.0);
  PointCloud second = test::sample_sphere(20000, 0.5, Vector3d(2.0, 0.0, 0.0));
  cloud.append(second);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> ux(-1.2, 2.7), uyz(-1.2, 1.2);
  std::normal_distribution<double> gauss;
  for (int c = 0; c < 80; ++c) {  // 80 clusters of 5 outliers (1 % of the points) off both spheres
    Vector3d centre;
    do centre = Vector3d(ux(rng), uyz(rng), uyz(rng));
    while (std::abs(centre.norm() - 1.0) < 0.2 || std::abs((centre - Vector3d(2.0, 0.0, 0.0)).norm() - 0.5) < 0.2);
    for (int k = 0; k < 5; ++k) {
      cloud.positions.push_back(centre + 0.05 * Vector3d(gauss(rng), gauss(rng), gauss(rng)));
      cloud.normals.push_back(Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized());
    }
  }
  PoissonParams params;
  params.depth = 7;
  const PoissonResult kept = [&] {
    PoissonParams all = params;
    all.unsupported_piece_gap = 0.0;
    return reconstruct_poisson(cloud, all);
  }();
  const PoissonResult cleaned = reconstruct_poisson(cloud, params);
  EXPECT_GT(kept.topology.components, 2u) << "the outliers raise no bubble: the test shows nothing";
  EXPECT_EQ(cleaned.topology.components, 2u);
  EXPECT_GT(cleaned.unsupported_pieces, 0u);
  EXPECT_EQ(cleaned.topology.boundary_edges, 0u);
  for (const Vector3d& v : cleaned.mesh.vertices.positions) {
    const double d = std::min(std::abs(v.norm() - 1.0), std::abs((v - Vector3d(2.0, 0.0, 0.0)).norm() - 0.5));
    EXPECT_LT(d, 0.05) << "a vertex away from both spheres";
    if (d >= 0.05) break;
  }
}

TEST(Poisson, ZeroAndNonFiniteNormalsAreSkippedAndCounted) {
  PointCloud sphere = test::sample_sphere(10000, 1.0);
  for (std::size_t i = 0; i < 100; ++i) sphere.normals[7 * i] = Vector3d::Zero();
  sphere.normals[1] = Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
  sphere.normals[2] = Vector3d(std::numeric_limits<double>::infinity(), 0.0, 0.0);
  PoissonParams params;
  params.depth = 6;
  const PoissonResult r = reconstruct_poisson(sphere, params);
  EXPECT_EQ(r.skipped_normals, 102u);
  EXPECT_TRUE(r.topology.watertight());
  EXPECT_EQ(r.topology.genus(), 0);
  const auto& counts = r.stats.counts;
  EXPECT_NE(std::find(counts.begin(), counts.end(), std::pair<std::string, std::size_t>("skipped_normals", 102)), counts.end());
}

TEST(Poisson, CarriesColoursAndFieldsFromTheNearestSample) {
  PointCloud sphere = test::sample_sphere(10000, 1.0);
  sphere.colors.resize(sphere.size());
  ScalarField& side = sphere.fields.add("side", sphere.size(), ScalarType::Int32);
  for (std::size_t i = 0; i < sphere.size(); ++i) {
    const bool top = sphere.positions[i].z() > 0.0;
    sphere.colors[i] = top ? Vector3f(1, 0, 0) : Vector3f(0, 0, 1);
    side.values[i] = top ? 1 : -1;
  }
  PoissonParams params;
  params.depth = 6;
  const PoissonResult r = reconstruct_poisson(sphere, params);
  ASSERT_EQ(r.mesh.vertices.colors.size(), r.mesh.vertex_count());
  const ScalarField* out = r.mesh.vertices.fields.find("side");
  ASSERT_NE(out, nullptr);
  EXPECT_EQ(out->type, ScalarType::Int32);
  for (std::size_t v = 0; v < r.mesh.vertex_count(); ++v) {
    const double z = r.mesh.vertices.positions[v].z();
    if (std::abs(z) < 0.1) continue;
    EXPECT_EQ(r.mesh.vertices.colors[v].x(), z > 0 ? 1.0f : 0.0f);
    EXPECT_EQ(out->values[v], z > 0 ? 1.0 : -1.0);
  }
}

TEST(Poisson, ErrorsNameTheProblem) {
  PointCloud few = test::sample_sphere(10, 1.0);
  for (std::size_t i = 0; i < 7; ++i) few.normals[i] = Vector3d::Zero();
  expect_error<InputError>([&] { reconstruct_poisson(few); }, "3 of 10 points have a usable normal");
  PointCloud bare = test::sample_sphere(100, 1.0);
  bare.normals.clear();
  expect_error<UsageError>([&] { reconstruct_poisson(bare); }, "no normals");
  PointCloud bad = test::sample_sphere(100, 1.0);
  bad.positions[5].x() = std::numeric_limits<double>::quiet_NaN();
  expect_error<InputError>([&] { reconstruct_poisson(bad); }, "point 5 has a non-finite coordinate");
  PoissonParams p;
  p.depth = 1;
  expect_error<UsageError>([&] { p.validate(); }, "depth must be 0 (from the data) or in [2, 16], got 1");
  p = {};
  p.point_weight = -1;
  expect_error<UsageError>([&] { p.validate(); }, "point_weight must be >= 0");
  p = {};
  p.samples_per_node = 0;
  expect_error<UsageError>([&] { p.validate(); }, "samples_per_node must be > 0");
  p = {};
  p.island_area_ratio = 2;
  expect_error<UsageError>([&] { p.validate(); }, "island_area_ratio must be in [0, 1]");
}

// Once the octree is known, the forecast predicts the output's triangles (bench/notes/progress.md:
// within 0.9-1.1x on 11 scans); the progress stays monotone, names its phases and ends at 1.
TEST(Poisson, ForecastsItsOutputAndReportsMonotoneProgress) {
  const PointCloud sphere = test::sample_sphere(30000, 1.0);
  std::vector<double> fractions;
  std::vector<ProgressForecast> forecasts;
  std::vector<std::string> phases;
  PhasedProgress progress;
  progress.on_fraction = [&](double f) {
    fractions.push_back(f);
    return true;
  };
  progress.on_phase = [&](std::string_view name) { phases.emplace_back(name); };
  progress.on_forecast = [&](const ProgressForecast& f) { forecasts.push_back(f); };
  PoissonParams params;
  params.depth = 8;
  const PoissonResult r = reconstruct_poisson(sphere, params, nullptr, progress);
  ASSERT_EQ(forecasts.size(), 1u);
  EXPECT_GT(forecasts[0].seconds, 0.0);
  const double triangles = double(r.mesh.triangle_count());
  EXPECT_GT(forecasts[0].output_size, 0.7 * triangles);
  EXPECT_LT(forecasts[0].output_size, 1.4 * triangles);
  ASSERT_GT(fractions.size(), 20u);
  for (std::size_t i = 1; i < fractions.size(); ++i) EXPECT_GE(fractions[i], fractions[i - 1]) << i;
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  for (const char* phase : {"octree", "splatting", "extraction", "density"})
    EXPECT_NE(std::find(phases.begin(), phases.end(), phase), phases.end()) << phase;
  // the same surface with or without a listener
  const PoissonResult quiet = reconstruct_poisson(sphere, params);
  EXPECT_EQ(quiet.mesh.triangles, r.mesh.triangles);
  // cancelled from inside the solver
  std::size_t calls = 0;
  EXPECT_THROW(reconstruct_poisson(sphere, params, nullptr, [&](double) { return ++calls < 10; }), CancelledError);
}

TEST(Poisson, DepthFromTheDataFollowsTheSpacing) {
  const PointCloud sphere = test::sample_sphere(20000, 1.0);  // spacing about 0.012: 2.2 / 0.012 = 2^7.5
  const PoissonResult r = reconstruct_poisson(sphere);
  EXPECT_GE(r.depth, 7);
  EXPECT_LE(r.depth, 8);
  EXPECT_TRUE(r.topology.watertight());
}

}  // namespace
}  // namespace pointsurf
