// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end tests of `pointsurf features` and `pointsurf clean`: the built command line on
// generated files, its outputs scored against truth known by construction (a cube's faces,
// edges and corners), its reports checked field by field.
#include <array>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pointsurf/features/feature_points.h"
#include "pointsurf/io/io.h"
#include "support/clean_shapes.h"
#include "support/cli_run.h"
#include "support/features_shapes.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

class CleanFeaturesCli : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Runs the command, expects exit 0, and returns the report of its one processing stage.
  nlohmann::json run_stage(const std::string& args, const std::string& type) {
    const test::RunResult r = test::run_cli(args + " --quiet --report " + path("report.json"), dir_);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.err;
    std::ifstream in(path("report.json"));
    const nlohmann::json report = nlohmann::json::parse(in, nullptr, false);
    if (report.is_discarded() || !report.contains("stages")) return {};
    for (const nlohmann::json& stage : report["stages"])
      if (stage.value("type", "") == type) return stage;
    ADD_FAILURE() << "no stage " << type << " in the report";
    return {};
  }
  std::filesystem::path dir_;
};

TEST_F(CleanFeaturesCli, FeaturesFindTheCubesEdgesAndAllEightCorners) {
  test::FeatureShape cube = test::sample_cube_features(40000, 1.0, 3);
  cube.cloud.normals.clear();
  write_point_cloud(path("cube.ply"), cube.cloud);
  const nlohmann::json stage = run_stage("features " + path("cube.ply") + " " + path("labelled.ply"), "features");
  const PointCloud out = read_point_cloud(path("labelled.ply")).cloud;
  ASSERT_EQ(out.size(), cube.cloud.size());
  EXPECT_EQ(out.positions, cube.cloud.positions);  // labels only
  const ScalarField* feature = out.fields.find("feature");
  ASSERT_NE(feature, nullptr);
  EXPECT_EQ(feature->type, ScalarType::UInt8);

  // Issue 13's scoring: truth within 0.5 spacing of an edge, a label right within 1.5.
  const double spacing = stage["metrics"]["mean_spacing"].get<double>();
  EXPECT_NEAR(spacing, mean_spacing(cube.cloud.positions), 1e-9 * spacing);
  const test::FeatureScore s = test::score_features(feature->values, cube.edge_distance, 0.5 * spacing, 1.5 * spacing);
  std::printf("cube through the CLI: precision %.3f recall %.3f (%zu labelled, %zu truth)\n", s.precision, s.recall, s.labelled, s.truth);
  EXPECT_GT(s.precision, 0.97);  // measured 0.99
  EXPECT_GT(s.recall, 0.95);     // measured 0.99
  std::size_t edges = 0, corners = 0;
  for (double v : feature->values) edges += v == 1.0, corners += v == 2.0;
  EXPECT_EQ(stage["counts"]["edges"].get<std::size_t>(), edges);
  EXPECT_EQ(stage["counts"]["corners"].get<std::size_t>(), corners);
  EXPECT_EQ(stage["counts"]["points"].get<std::size_t>(), cube.cloud.size());

  // Every one of the eight corners has a point labelled Corner within 5 spacings, and no point
  // farther than 6 spacings from a corner is labelled Corner (measured: the farthest at 4.7; the
  // three fitted planes meet a few spacings off the corner, their clusters being small there).
  std::array<int, 8> found{};
  std::array<std::array<int, 3>, 8> near_labels{};  // labels within 5 spacings of each corner
  for (std::size_t i = 0; i < out.size(); ++i) {
    const Vector3d& q = out.positions[i];
    if (cube.corner_distance[i] <= 5.0 * spacing) ++near_labels[(q.x() > 0) + 2 * (q.y() > 0) + 4 * (q.z() > 0)][int(feature->values[i])];
    if (feature->values[i] != double(FeatureLabel::Corner)) continue;
    EXPECT_LT(cube.corner_distance[i], 6.0 * spacing) << "a corner label far from every corner at point " << i;
    const Vector3d& p = out.positions[i];
    const int octant = (p.x() > 0) + 2 * (p.y() > 0) + 4 * (p.z() > 0);
    if (cube.corner_distance[i] <= 5.0 * spacing) ++found[octant];
  }
  // All eight. Before the far-corner pass one (x > 0, y < 0, z < 0) was missed: no candidate's
  // own three planes met within 2 dd of it.
  int corners_found = 0;
  for (int c = 0; c < 8; ++c) {
    corners_found += found[c] > 0;
    if (found[c] == 0)
      std::printf("corner %d (octant bits x, y, z) not found; within 5 spacings: %d none, %d edge, %d corner points\n", c,
                  near_labels[c][0], near_labels[c][1], near_labels[c][2]);
  }
  EXPECT_EQ(corners_found, 8);
}

TEST_F(CleanFeaturesCli, FeaturesReportPrecisionAndRecallOfATruthField) {
  test::FeatureShape cube = test::sample_cube_features(20000, 1.0, 5);
  cube.cloud.normals.clear();
  const double spacing = mean_spacing(cube.cloud.positions);
  ScalarField& truth = cube.cloud.fields.add("truth", cube.cloud.size(), ScalarType::UInt8);
  for (std::size_t i = 0; i < cube.cloud.size(); ++i) truth.values[i] = cube.edge_distance[i] <= spacing;
  write_point_cloud(path("cube.ply"), cube.cloud);
  const nlohmann::json stage = run_stage("features " + path("cube.ply") + " " + path("labelled.ply") + " --truth-field truth", "features");
  const PointCloud out = read_point_cloud(path("labelled.ply")).cloud;
  const std::vector<double>& labels = out.fields.find("feature")->values;
  std::size_t labelled = 0, expected = 0, both = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    labelled += labels[i] != 0.0, expected += truth.values[i] != 0.0;
    both += labels[i] != 0.0 && truth.values[i] != 0.0;
  }
  ASSERT_GT(labelled, 0u);
  EXPECT_NEAR(stage["metrics"]["precision"].get<double>(), double(both) / double(labelled), 1e-12) << stage.dump();
  EXPECT_NEAR(stage["metrics"]["recall"].get<double>(), double(both) / double(expected), 1e-12) << stage.dump();
}

// A noisy cube with PCA normals from `pointsurf normals`, as a scanner pipeline would give.
struct NoisyCube {
  PointCloud clean;
  double spacing = 0.0;
};

NoisyCube write_noisy_cube(const std::string& file, double noise_in_spacings, std::uint64_t seed) {
  NoisyCube c;
  c.clean = test::sample_cube(30000, 1.0, seed);
  c.clean.normals.clear();
  c.spacing = mean_spacing(c.clean.positions);
  PointCloud noisy = c.clean;
  test::add_noise(noisy, noise_in_spacings * c.spacing, seed + 1);
  write_point_cloud(file, noisy);
  return c;
}

// RMS distance to the true cube of the points whose clean sample lies within 2 spacings of an
// edge, and of those farther than 5.
std::array<double, 2> cube_rms(const PointCloud& cloud, const NoisyCube& c) {
  std::vector<bool> edge(cloud.size()), flat(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double e = test::distance_to_cube_edge(c.clean.positions[i]);
    edge[i] = e <= 2.0 * c.spacing;
    flat[i] = e > 5.0 * c.spacing;
  }
  auto d = [](const Vector3d& p) { return test::distance_to_cube(p); };
  return {test::rms_distance(cloud.positions, d, edge), test::rms_distance(cloud.positions, d, flat)};
}

TEST_F(CleanFeaturesCli, TrilateralCleanDenoisesTheCubeAndKeepsItsEdgesBetterThanBilateral) {
  const NoisyCube c = write_noisy_cube(path("noisy.ply"), 0.5, 21);
  run_stage("normals " + path("noisy.ply") + " " + path("with_normals.ply"), "normals");
  const nlohmann::json tri = run_stage("clean " + path("with_normals.ply") + " " + path("tri.ply") + " --method trilateral", "clean");
  run_stage("clean " + path("with_normals.ply") + " " + path("bi.ply") + " --method bilateral", "clean");
  const PointCloud before = read_point_cloud(path("with_normals.ply")).cloud;
  const PointCloud t = read_point_cloud(path("tri.ply")).cloud, b = read_point_cloud(path("bi.ply")).cloud;
  ASSERT_EQ(t.size(), c.clean.size());  // smoothing moves points, it removes none
  ASSERT_EQ(b.size(), c.clean.size());
  ASSERT_EQ(t.normals.size(), t.size());
  for (const Vector3d& n : t.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-6);
  const auto rms0 = cube_rms(before, c), rt = cube_rms(t, c), rb = cube_rms(b, c);
  std::printf("cube RMS near edges / flat: input %.5f / %.5f, bilateral %.5f / %.5f, trilateral %.5f / %.5f\n", rms0[0], rms0[1], rb[0],
              rb[1], rt[0], rt[1]);
  EXPECT_LT(rt[1], 0.45 * rms0[1]);  // flat faces: measured 0.32x of the noise
  EXPECT_LT(rt[0], 0.88 * rms0[0]);  // near edges: measured 0.80x (bilateral 0.92x)
  EXPECT_LT(rt[0], 0.93 * rb[0]);    // near edges against bilateral: measured 0.87x
  EXPECT_LT(rt[1], 1.02 * rb[1]);    // flat: no worse than bilateral (measured 0.98x)
  // The report carries what was used and what moved.
  EXPECT_GT(tri["counts"].value("moved", std::size_t(0)) + tri["counts"].value("trilateral.moved", std::size_t(0)), 0u) << tri.dump();
}

TEST_F(CleanFeaturesCli, DefaultCleanRemovesFarOutliersAndKeepsTheSurface) {
  PointCloud cube = test::sample_cube(30000, 1.0, 31);
  const std::size_t surface = cube.size();
  const std::vector<std::uint32_t> outliers =
      test::add_scattered_outliers(cube, 60, 1.0, 0.3, [](const Vector3d& p) { return test::distance_to_cube(p); }, 32);
  cube.normals.clear();
  write_point_cloud(path("scan.ply"), cube);
  const nlohmann::json stage = run_stage("clean " + path("scan.ply") + " " + path("kept.ply"), "clean");
  const PointCloud kept = read_point_cloud(path("kept.ply")).cloud;
  std::size_t outliers_kept = 0, surface_kept = 0;
  for (const Vector3d& p : kept.positions) (test::distance_to_cube(p) < 1e-9 ? surface_kept : outliers_kept) += 1;
  std::printf("default clean: kept %zu of %zu surface points and %zu of %zu outliers\n", surface_kept, surface, outliers_kept, outliers.size());
  EXPECT_EQ(outliers_kept, 0u);
  EXPECT_GE(double(surface_kept), 0.997 * double(surface));  // issue 13: at most 0.3 % of a clean scan
  EXPECT_EQ(kept.size(), surface_kept + outliers_kept);
  EXPECT_FALSE(stage.empty());
}

}  // namespace
}  // namespace pointsurf
