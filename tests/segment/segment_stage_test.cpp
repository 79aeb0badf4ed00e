// SPDX-License-Identifier: GPL-3.0-or-later
// The segment stage end to end through the command line.
#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pointsurf/io/io.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/cli_run.h"
#include "support/files.h"
#include "support/primitive_scene.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(SegmentStage, RansacWritesTheFieldAndListsPrimitives) {
  const std::filesystem::path dir = test::temp_dir("segment_stage_ransac");
  const test::PrimitiveScene scene = test::make_primitive_scene(150.0);
  write_point_cloud(dir / "scene.ply", scene.cloud);
  const test::RunResult r = test::run_cli("segment " + (dir / "scene.ply").string() + " " + (dir / "out.ply").string() + " --method ransac --report " + (dir / "report.json").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud out = read_point_cloud(dir / "out.ply").cloud;
  const ScalarField* field = out.fields.find("segment");
  ASSERT_NE(field, nullptr);
  std::map<int, std::size_t> counts;
  for (double v : field->values) ++counts[int(v)];
  EXPECT_GE(counts.size(), 5u);
  const std::string report = test::read_bytes(dir / "report.json");
  for (const char* type : {"plane", "sphere", "cylinder", "cone"}) EXPECT_TRUE(test::contains(report, type)) << type;
}

TEST(SegmentStage, RegionEuclideanAndErrors) {
  const std::filesystem::path dir = test::temp_dir("segment_stage_region");
  write_point_cloud(dir / "cube.ply", test::sample_cube(6000, 1.0, 2));
  const std::string cube = (dir / "cube.ply").string(), out = " " + (dir / "out.ply").string();
  EXPECT_EQ(test::run_cli("segment " + cube + out, dir).exit_code, 0);
  EXPECT_EQ(test::run_cli("segment " + cube + out + " --method euclidean", dir).exit_code, 0);
  const test::RunResult hk = test::run_cli("segment " + cube + out + " --method hk", dir);
  EXPECT_EQ(hk.exit_code, 2);
  EXPECT_TRUE(test::contains(hk.err, "surface_type")) << hk.err;
  const test::RunResult bad = test::run_cli("segment " + cube + out + " --method region --max-angle-deg 120", dir);
  EXPECT_EQ(bad.exit_code, 1);
  const test::RunResult types = test::run_cli("segment " + cube + out + " --method ransac --types plane,ellipsoid", dir);
  EXPECT_EQ(types.exit_code, 1);
  EXPECT_TRUE(test::contains(types.err, "ellipsoid")) << types.err;
}

// Keys of the previous release still work in a pipeline, with a warning in the report: the
// same output as the new key's.
TEST(SegmentStage, FormerKeysGiveTheSameOutputWithAWarning) {
  const std::filesystem::path dir = test::temp_dir("segment_stage_former_keys");
  write_point_cloud(dir / "cube.ply", test::sample_cube(6000, 1.0, 2));
  const auto run = [&](const std::string& name, const std::string& step) {
    const std::filesystem::path pipeline = dir / (name + "_pipeline.json");
    test::write_bytes(pipeline, "[\"" + (dir / "cube.ply").string() + "\", " + step + ", \"" + (dir / (name + ".ply")).string() + "\"]");
    const test::RunResult r = test::run_cli("run " + pipeline.string() + " --report " + (dir / (name + ".json")).string(), dir);
    EXPECT_EQ(r.exit_code, 0) << step << ": " << r.err;
    return test::read_bytes(dir / (name + ".json"));
  };
  const auto same_output = [&](const std::string& a, const std::string& b) {
    const std::string x = test::read_bytes(dir / (a + ".ply")), y = test::read_bytes(dir / (b + ".ply"));
    return !x.empty() && x == y;
  };
  const std::string new_key = run("new", R"({"type": "segment", "method": "euclidean", "radius": "4sp"})");
  const std::string old_key = run("old", R"({"type": "segment", "method": "euclidean", "radius_in_spacings": 4})");
  EXPECT_TRUE(same_output("new", "old"));
  EXPECT_FALSE(test::contains(new_key, "deprecated"));
  EXPECT_TRUE(test::contains(old_key, R"(key \"radius_in_spacings\" is deprecated)")) << old_key;
  run("new2", R"({"type": "segment", "method": "ransac", "max_normal_angle_deg": 20, "epsilon": "1.5sp"})");
  const std::string old2 = run("old2", R"({"type": "segment", "method": "ransac", "max_normal_deg": 20, "epsilon_in_spacings": 1.5})");
  EXPECT_TRUE(same_output("new2", "old2"));
  EXPECT_TRUE(test::contains(old2, R"(key \"max_normal_deg\" is deprecated)")) << old2;
  EXPECT_TRUE(test::contains(old2, R"(key \"epsilon_in_spacings\" is deprecated)")) << old2;
}

}  // namespace
}  // namespace pointsurf

namespace pointsurf {
namespace {

TEST(BoundaryStage, MarksTheRimAndWritesOutlines) {
  const std::filesystem::path dir = test::temp_dir("boundary_stage");
  PointCloud plate = test::sample_plane(20000, 1.0, 6);
  write_point_cloud(dir / "plate.ply", plate);
  const std::string out = (dir / "out.ply").string(), lines = (dir / "lines.geojson").string();
  const test::RunResult r =
      test::run_cli("boundary " + (dir / "plate.ply").string() + " " + out + " --outlines " + lines + " --crs EPSG:25832 --report " + (dir / "r.json").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud got = read_point_cloud(out).cloud;
  const ScalarField* b = got.fields.find("boundary");
  ASSERT_NE(b, nullptr);
  std::size_t rim = 0, marked = 0, both = 0, recalled = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    // Mean spacing about 0.007: points within 0.005 of the rim should be marked, and marked
    // points should mostly lie within 0.03 of it.
    const double depth = 1.0 - got.positions[i].cwiseAbs().head<2>().maxCoeff();
    const bool on = b->values[i] != 0;
    rim += depth < 0.005, marked += on, both += on && depth < 0.03;
    recalled += on && depth < 0.005;
  }
  EXPECT_GT(double(recalled), 0.5 * double(rim));
  EXPECT_GT(double(both), 0.8 * double(marked));  // random samples leave wide gaps at ~0.5 % of interior points
  // The plate's outline is one closed loop: a Polygon, counter-clockwise, around the square.
  const nlohmann::json geo = nlohmann::json::parse(test::read_bytes(lines));
  EXPECT_EQ(geo["crs"]["properties"]["name"], "EPSG:25832");
  ASSERT_EQ(geo["features"].size(), 1u);
  EXPECT_EQ(geo["features"][0]["geometry"]["type"], "Polygon");
  const nlohmann::json& ring = geo["features"][0]["geometry"]["coordinates"][0];
  ASSERT_GE(ring.size(), 5u);
  EXPECT_EQ(ring.front(), ring.back());
  double twice_area = 0.0, reach = 0.0;
  for (std::size_t i = 0; i + 1 < ring.size(); ++i) {
    const double x0 = ring[i][0], y0 = ring[i][1], x1 = ring[i + 1][0], y1 = ring[i + 1][1];
    twice_area += x0 * y1 - x1 * y0;
    reach = std::max(reach, std::max(std::abs(x0), std::abs(y0)));
  }
  EXPECT_NEAR(0.5 * twice_area, 4.0, 0.2);  // positive: counter-clockwise
  EXPECT_NEAR(reach, 1.0, 0.05);
  const test::RunResult bad = test::run_cli("boundary " + (dir / "plate.ply").string() + " " + out + " --outlines " + (dir / "x.dxf").string(), dir);
  EXPECT_NE(bad.exit_code, 0);
}

// RANSAC finds a rough plate (within +-2 mean spacings of its plane, epsilon 3 spacings) as a
// plane. In a pipeline, boundary outlines it on RANSAC's own plane and band. From a file (no
// planes) the least-squares test skips it, and boundary says so: how many, why, which knob.
TEST(BoundaryStage, OutlinesRansacPlanesOnTheirOwnBandAndSaysWhatItSkips) {
  const std::filesystem::path dir = test::temp_dir("boundary_ransac");
  PointCloud plate = test::sample_plane(20000, 1.0, 6);
  const double spacing = mean_spacing(plate.positions);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> rough(-2.0 * spacing, 2.0 * spacing);
  for (Eigen::Vector3d& p : plate.positions) p.z() += rough(rng);
  write_point_cloud(dir / "plate.ply", plate);
  const std::string pipeline = "[\"" + (dir / "plate.ply").string() +
                               "\", {\"type\": \"segment\", \"method\": \"ransac\", \"types\": \"plane\", \"epsilon\": \"3sp\"}, \"" +
                               (dir / "seg.ply").string() + "\", {\"type\": \"boundary\", \"outlines\": \"" + (dir / "a.geojson").string() + "\"}]";
  test::write_bytes(dir / "p.json", pipeline);
  const test::RunResult r = test::run_cli("run " + (dir / "p.json").string() + " --quiet --report " + (dir / "r.json").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(dir / "r.json"));
  const nlohmann::json* seg = nullptr;
  const nlohmann::json* bnd = nullptr;
  for (const nlohmann::json& st : report["stages"]) {
    if (st["type"] == "segment") seg = &st;
    if (st["type"] == "boundary") bnd = &st;
  }
  ASSERT_TRUE(seg && bnd);
  ASSERT_EQ((*seg)["counts"]["segments"], 1) << seg->dump();
  EXPECT_EQ((*bnd)["counts"]["outlines"], 1) << bnd->dump();
  EXPECT_EQ((*bnd)["counts"]["nonplanar_segments"], 0);
  // The same labels read back from the file: no planes, the 0.5-spacing RMS test, a warning.
  const test::RunResult f = test::run_cli("boundary " + (dir / "seg.ply").string() + " " + (dir / "b.ply").string() + " --report " +
                                              (dir / "f.json").string(), dir);
  ASSERT_EQ(f.exit_code, 0) << f.err;
  const nlohmann::json file_report = nlohmann::json::parse(test::read_bytes(dir / "f.json"));
  nlohmann::json fb;
  for (const nlohmann::json& st : file_report["stages"])
    if (st["type"] == "boundary") fb = st;
  EXPECT_EQ(fb["counts"]["outlines"], 0) << fb.dump();
  EXPECT_EQ(fb["counts"]["nonplanar_segments"], 1);
  EXPECT_TRUE(test::contains(f.err, "1 of 1 segments have no outline: 1 not planar")) << f.err;
  EXPECT_TRUE(test::contains(f.err, "max_rms_in_spacings 0.5")) << f.err;
}

}  // namespace
}  // namespace pointsurf
