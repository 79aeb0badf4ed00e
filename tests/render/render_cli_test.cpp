// SPDX-License-Identifier: GPL-3.0-or-later
// `pointsurf render IN OUT.png` and the render stage in a pipeline.
#include <gtest/gtest.h>

#include "pointsurf/io/io.h"
#include "pointsurf/render/image.h"

#include <nlohmann/json.hpp>
#include "support/cli_run.h"
#include "support/files.h"
#include "support/mesh_shapes.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

Image read_png(const std::filesystem::path& path) {
  const std::string bytes = test::read_bytes(path);
  return decode_png(std::vector<std::uint8_t>(bytes.begin(), bytes.end()), path.string());
}

TEST(RenderCli, WritesAPictureOfTheAskedSize) {
  const auto dir = test::temp_dir("render_cli");
  write_mesh(dir / "sphere.off", test::icosphere_mesh(3));
  const std::string in = (dir / "sphere.off").string(), out = (dir / "sphere.png").string();
  test::RunResult r = test::run_cli("render " + in + " " + out + " --size 320x200 --view front --wireframe --quiet", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  Image img = read_png(out);
  EXPECT_EQ(img.width, 320);
  EXPECT_EQ(img.height, 200);
  // Colour by a coordinate; the report says what was drawn.
  r = test::run_cli("render " + in + " " + out + " --field z --report " + (dir / "r.json").string() + " --quiet", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = test::read_bytes(dir / "r.json");
  EXPECT_TRUE(test::contains(report, "\"triangles_drawn\": 1280")) << report;
  EXPECT_TRUE(test::contains(report, "\"colormap\": \"sequential\""));
  EXPECT_EQ(read_png(out).width, 1024);
}

TEST(RenderCli, BadOptionsAndInputsExitWithTheirCodes) {
  const auto dir = test::temp_dir("render_cli_errors");
  write_point_cloud(dir / "c.ply", test::sample_sphere(200));
  const std::string in = (dir / "c.ply").string(), out = (dir / "c.png").string();
  test::RunResult r = test::run_cli("render " + in + " " + out + " --size 300", dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--size: \"300\" is not WIDTHxHEIGHT")) << r.err;
  r = test::run_cli("render " + in + " " + out + " --view bottom", dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "\"bottom\" is not one of front, side, top or iso")) << r.err;
  r = test::run_cli("render " + in + " " + out + " --field deviation", dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(test::contains(r.err, "no field \"deviation\"")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  r = test::run_cli("render " + in + " " + (dir / "c.ply").string(), dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "c.ply: expected a .png file name")) << r.err;
  r = test::run_cli("render " + in + " " + (dir / "missing" / "c.png").string(), dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "does not exist")) << r.err;
}

TEST(RenderCli, PipelineRendersAndPassesItsInputOn) {
  const auto dir = test::temp_dir("render_pipeline");
  write_point_cloud(dir / "c.ply", test::sample_sphere(500));
  const std::string pipeline = "[\"" + (dir / "c.ply").string() + "\", {\"type\": \"render\", \"filename\": \"" + (dir / "a.png").string() +
                               "\", \"view\": \"top\", \"size\": \"200x150\"}, {\"type\": \"normals\", \"k\": 12}, \"" + (dir / "n.ply").string() +
                               "\", {\"type\": \"render\", \"filename\": \"" + (dir / "b.png").string() + "\", \"size\": \"100x80\"}]";
  test::write_bytes(dir / "p.json", pipeline);
  const test::RunResult r = test::run_cli("run " + (dir / "p.json").string() + " --quiet", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_png(dir / "a.png").width, 200);
  EXPECT_EQ(read_png(dir / "b.png").height, 80);
  EXPECT_TRUE(std::filesystem::exists(dir / "n.ply"));
  // The command gives the same bytes as the pipeline, whatever the threads.
  const test::RunResult c = test::run_cli("render " + (dir / "c.ply").string() + " " + (dir / "cli.png").string() +
                                              " --view top --size 200x150 --threads 1 --quiet", dir);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(test::read_bytes(dir / "cli.png"), test::read_bytes(dir / "a.png"));
}

// After evaluate, render colours by its deviation with its tolerance, unless told otherwise.
TEST(RenderCli, AfterEvaluateTakesItsFieldAndTolerance) {
  const auto dir = test::temp_dir("render_after_evaluate");
  write_point_cloud(dir / "c.ply", test::sample_sphere(800));
  const auto png = [&](const char* name) { return (dir / name).string(); };
  const std::string pipeline = "[\"" + (dir / "c.ply").string() + "\", {\"type\": \"normals\", \"k\": 12}, {\"type\": \"reconstruct\", \"method\": "
                               "\"triangulate\"}, {\"type\": \"evaluate\", \"tolerance\": 0.003}, {\"type\": \"render\", \"filename\": \"" +
                               png("a.png") + "\", \"size\": \"160x120\"}, {\"type\": \"render\", \"filename\": \"" + png("b.png") +
                               "\", \"size\": \"160x120\", \"tolerance\": 0.001}, {\"type\": \"render\", \"filename\": \"" + png("c.png") +
                               "\", \"size\": \"160x120\", \"field\": \"z\"}]";
  test::write_bytes(dir / "p.json", pipeline);
  const test::RunResult r = test::run_cli("run " + (dir / "p.json").string() + " --quiet --report " + (dir / "r.json").string(), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(dir / "r.json"));
  std::vector<nlohmann::json> renders;
  for (const nlohmann::json& st : report["stages"])
    if (st["type"] == "render") renders.push_back(st["metrics"]);
  ASSERT_EQ(renders.size(), 3u);
  EXPECT_EQ(renders[0]["colormap"], "diverging");
  EXPECT_DOUBLE_EQ(renders[0]["scale_tolerance"].get<double>(), 0.003);
  EXPECT_GE(renders[0]["scale_max"].get<double>(), 0.006);  // at least twice the tolerance
  EXPECT_DOUBLE_EQ(renders[1]["scale_tolerance"].get<double>(), 0.001);  // given
  EXPECT_EQ(renders[2]["colormap"], "sequential");                         // another field given
}

}  // namespace
}  // namespace pointsurf
