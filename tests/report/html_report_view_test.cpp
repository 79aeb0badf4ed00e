// SPDX-License-Identifier: GPL-3.0-or-later
// The report's view model alone: what is shown, read from a hand-made run report, with no HTML.
#include "report/detail/html_report_view.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "pointsurf/render/colormap.h"
#include "pointsurf/evaluate/deviation_stats.h"
#include "support/files.h"
#include "support/mesh_shapes.h"
#include "support/shapes.h"

namespace pointsurf::detail {
namespace {

using nlohmann::json;

json stage(int index, const std::string& type, const std::string& tag, json inputs) {
  return {{"index", index}, {"type", type}, {"tag", tag}, {"inputs", inputs}, {"parameters", json::object()}, {"counts", json::object()},
          {"metrics", json::object()}, {"warnings", json::array()}, {"seconds", 0.25 * index}, {"peak_rss_mb", 10.0 * index},
          {"rss_rise_mb", 1.5}};
}

// Read a scan, reconstruct (a named tag, a warning with markup), evaluate with a known
// deviation block (default tag).
json run_report() {
  json read = stage(1, "read", "in", json::array());
  read["parameters"] = {{"filename", "scan.ply"}};
  read["counts"] = {{"points", 2000}};
  json mesh = stage(2, "reconstruct", "mesh", {"in"});
  mesh["parameters"] = {{"method", "ball-pivot"}, {"radius", {{"value", 3}, {"unit", "spacings"}}}};
  mesh["counts"] = {{"triangles", 5120}};
  mesh["warnings"] = {"3 holes left <script>x</script>"};
  json evaluate = stage(3, "evaluate", "evaluate3", {"mesh", "in"});
  evaluate["metrics"] = {{"deviation",
                          {{"count", 2000}, {"max_positive", 0.02}, {"max_negative", -0.03}, {"rms", 0.01}, {"tolerance", 0.005},
                           {"within_tolerance", 0.6}, {"extra", 1}, {"histogram", {{"edges", {-0.03, -0.01, 0.01, 0.03}}, {"counts", {100, 1800, 100}}}}}}};
  return {{"command", "run"},   {"version", "0.1.0"},  {"pipeline", "p.json"},
          {"status", "ok"},     {"total_seconds", 0.73}, {"peak_rss_mb", 45.0},
          {"outputs", {"mesh.ply", "deviation.ply"}},  {"warnings", {"stage 2 (reconstruct): 3 holes left <script>x</script>"}},
          {"stages", {read, mesh, evaluate}}};
}

HtmlReportInputs inputs(const json& report = run_report()) {
  HtmlReportInputs in;
  in.run_json = report.dump();
  in.origin = "run.json";
  in.three_js = "/* three */";
  return in;
}

TEST(HtmlReportView, SummaryAndStagesAreTheRunReportsValues) {
  const HtmlReportView v = html_report_view(inputs());
  EXPECT_EQ(v.title, "run.json");
  EXPECT_EQ(v.summary.pipeline, "p.json");
  EXPECT_EQ(v.summary.command, "run");
  EXPECT_EQ(v.summary.status, "ok");
  EXPECT_EQ(v.summary.version, "0.1.0");
  EXPECT_DOUBLE_EQ(v.summary.total_seconds, 0.73);
  EXPECT_DOUBLE_EQ(v.summary.peak_rss_mb, 45.0);
  EXPECT_EQ(v.summary.outputs, "[mesh.ply, deviation.ply]");
  EXPECT_FALSE(v.summary.error);

  ASSERT_EQ(v.stages.size(), 3u);
  EXPECT_EQ(v.stages[0].chart_label, "1 in");        // a tag of its own
  EXPECT_EQ(v.stages[1].chart_label, "2 mesh");
  EXPECT_EQ(v.stages[2].chart_label, "3 evaluate");  // the default tag repeats the type
  EXPECT_EQ(v.stages[2].inputs, "[mesh, in]");
  EXPECT_DOUBLE_EQ(v.stages[2].seconds, 0.75);
  EXPECT_DOUBLE_EQ(v.stages[2].peak_rss_mb, 30.0);
  EXPECT_DOUBLE_EQ(v.stages[2].rss_rise_mb, 1.5);
  EXPECT_FALSE(v.stages[1].expanded);
  EXPECT_TRUE(v.stages[2].expanded);
  // Nested parameters are flattened with "/"; numbers in 6 significant digits.
  const TextRows parameters = {{"method", "ball-pivot"}, {"radius/unit", "spacings"}, {"radius/value", "3"}};
  EXPECT_EQ(v.stages[1].parameters, parameters);
  EXPECT_EQ(v.stages[1].counts_and_metrics, (TextRows{{"triangles", "5120"}}));
  // Texts stay as written: escaping is the page's.
  EXPECT_EQ(v.stages[1].warnings, std::vector<std::string>{"3 holes left <script>x</script>"});
  EXPECT_EQ(v.warnings, std::vector<std::string>{"stage 2 (reconstruct): 3 holes left <script>x</script>"});
  EXPECT_EQ(v.run_report, run_report());
  EXPECT_EQ(v.three_js, "/* three */");
}

// The table's rows are the headline members of the deviation's declaration, in its order: a
// block holding every member of DeviationStats shows the eleven summary values, not the counts
// of each side nor the percentiles and histogram.
TEST(HtmlReportView, DeviationRowsAreTheDeclaredHeadlineMembers) {
  DeviationStats d;
  d.count = 10;
  d.positive = 6;
  d.rms = 0.25;
  d.percentile_ranks = {50.0};
  d.percentile_values = {0.1};
  json block = json::object();
  DeviationStats::results().record(d, [&](std::string key, ResultValue v) {
    json value = std::visit([](const auto& x) { return json(x); }, v);
    block[json::json_pointer("/" + key)] = value;
  });
  json r = run_report();
  r["stages"][2]["metrics"]["deviation"] = block;
  const HtmlReportView v = html_report_view(inputs(r));
  std::vector<std::string> keys;
  for (const auto& [key, text] : v.deviation.statistics) keys.push_back(key);
  // The share out of tolerance comes first, then the robust sizes beside the extremes.
  EXPECT_EQ(keys, (std::vector<std::string>{"count", "out_of_tolerance", "above_tolerance", "below_tolerance", "tolerance", "within_tolerance",
                                            "abs_p95", "abs_p99", "max_positive", "max_negative", "mean_positive", "mean_negative", "mean",
                                            "mean_absolute", "rms", "std"}));
  EXPECT_EQ(v.deviation.statistics[0].second, "10");
  EXPECT_EQ(v.deviation.statistics[14].second, "0.25");
}

TEST(HtmlReportView, DeviationIsTheEvaluateStagesBlock) {
  const HtmlReportView v = html_report_view(inputs());
  EXPECT_TRUE(v.deviation.evaluated);
  EXPECT_DOUBLE_EQ(v.deviation.tolerance, 0.005);
  // The known keys present, in the table's order; others ("extra", "histogram") are left out.
  const TextRows statistics = {{"count", "2000"},         {"tolerance", "0.005"}, {"within_tolerance", "0.6"},
                               {"max_positive", "0.02"}, {"max_negative", "-0.03"}, {"rms", "0.01"}};
  EXPECT_EQ(v.deviation.statistics, statistics);
  ASSERT_TRUE(v.deviation.histogram);
  ASSERT_EQ(v.deviation.histogram->centres.size(), 3u);
  EXPECT_NEAR(v.deviation.histogram->centres[0], -0.02, 1e-15);
  EXPECT_NEAR(v.deviation.histogram->centres[1], 0.0, 1e-15);
  EXPECT_NEAR(v.deviation.histogram->centres[2], 0.02, 1e-15);
  EXPECT_EQ(v.deviation.histogram->counts, json({100, 1800, 100}));
  EXPECT_EQ(v.deviation.histogram->colors.size(), 3u);
  // The last evaluate stage's block is shown; without its own tolerance the earlier one's stays.
  json r = run_report();
  json again = r["stages"][2];
  again["index"] = 4;
  again["tag"] = "second";
  again["metrics"]["deviation"] = {{"rms", 0.5}};
  r["stages"].push_back(again);
  const HtmlReportView w = html_report_view(inputs(r));
  EXPECT_EQ(w.deviation.statistics, (TextRows{{"rms", "0.5"}}));
  EXPECT_FALSE(w.deviation.histogram);
  EXPECT_DOUBLE_EQ(w.deviation.tolerance, 0.005);
}

TEST(HtmlReportView, WithoutEvaluateOrGeometryNothingIsShown) {
  json r = run_report();
  r["stages"].erase(2);
  const HtmlReportView v = html_report_view(inputs(r));
  EXPECT_FALSE(v.deviation.evaluated);
  EXPECT_TRUE(v.deviation.statistics.empty());
  EXPECT_FALSE(v.deviation.histogram);
  EXPECT_EQ(v.deviation.tolerance, 0.0);
  EXPECT_FALSE(v.legend);
  EXPECT_FALSE(v.mesh);
  EXPECT_FALSE(v.cloud);
  EXPECT_TRUE(v.pictures.empty());
  EXPECT_TRUE(v.notes.empty());
  // A report with nothing in it: defaults, not errors.
  const HtmlReportView e = html_report_view(inputs(json::object()));
  EXPECT_EQ(e.summary.status, "?");
  EXPECT_EQ(e.summary.outputs, "[]");
  EXPECT_TRUE(e.stages.empty());
}

TEST(HtmlReportView, AFailedRunShowsItsError) {
  json r = run_report();
  r["status"] = "failed";
  r["error"] = {{"message", "stage 2: no triangles"}};
  const HtmlReportView v = html_report_view(inputs(r));
  EXPECT_EQ(v.summary.status, "failed");
  ASSERT_TRUE(v.summary.error);
  EXPECT_EQ(*v.summary.error, "stage 2: no triangles");
}

TEST(HtmlReportView, GeometryIsColouredByDeviationAboutItsCentre) {
  HtmlReportInputs in = inputs();
  const Vector3d at(5e5, 4e6, 100);
  const TriangleMesh sphere = test::icosphere_mesh(2, 1.0, at);
  in.mesh.vertices.positions = sphere.vertices.positions;
  in.mesh.triangles = sphere.triangles;
  in.cloud = test::sample_sphere(500, 1.0, at);
  ScalarField& d = in.cloud.fields.add("deviation", in.cloud.size());
  for (std::size_t i = 0; i < d.values.size(); ++i) d.values[i] = in.cloud.positions[i].z() > at.z() ? 0.0075 : -0.0075;
  HtmlReportParams params;
  params.view_width = 64;
  params.view_height = 48;
  const HtmlReportView v = html_report_view(in, params);

  EXPECT_NEAR(v.centre[1], 4e6, 0.1);
  EXPECT_NEAR(v.radius, std::sqrt(3.0), 0.1);
  ASSERT_TRUE(v.mesh);
  EXPECT_EQ(v.mesh->vertices, sphere.vertices.positions.size());
  EXPECT_EQ(v.mesh->triangles, sphere.triangles.size());
  EXPECT_EQ(v.mesh->positions.size(), 3 * sphere.vertices.positions.size());
  EXPECT_EQ(v.mesh->indices.size(), 3 * sphere.triangles.size());
  EXPECT_EQ(v.mesh->colors.size(), 3 * sphere.vertices.positions.size());
  EXPECT_NEAR(v.mesh->positions[1], sphere.vertices.positions[0].y() - v.centre[1], 1e-6);
  ASSERT_TRUE(v.cloud);
  EXPECT_EQ(v.cloud->points, 500u);
  EXPECT_EQ(v.cloud->colors.size(), 1500u);
  // The legend: symmetric about 0, with evaluate's tolerance as the band.
  ASSERT_TRUE(v.legend);
  EXPECT_DOUBLE_EQ(v.legend->min, -v.legend->max);
  EXPECT_DOUBLE_EQ(v.legend->tolerance, 0.005);
  EXPECT_EQ(v.legend->stops.size(), 21u);
  EXPECT_NE(v.legend->stops.front(), v.legend->stops.back());
  EXPECT_EQ(v.legend->over, ColorScale::kOverRange);
  EXPECT_EQ(v.legend->under, ColorScale::kUnderRange);
  // A vertex shows the deviation of the points measured against its triangles: well above the
  // equator they are all +0.0075, so it has the colour of such a point (the cloud's first one
  // above the equator), and well below that of a -0.0075 point.
  std::size_t up = 0, down = 0;
  while (in.cloud.positions[up].z() <= at.z()) ++up;
  while (in.cloud.positions[down].z() > at.z()) ++down;
  for (std::size_t j = 0; j < sphere.vertices.positions.size(); ++j) {
    const double z = sphere.vertices.positions[j].z() - at.z();
    if (std::abs(z) < 0.5) continue;
    const std::size_t point = z > 0 ? up : down;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(v.mesh->colors[3 * j + std::size_t(k)], v.cloud->colors[3 * point + std::size_t(k)]) << "vertex " << j;
  }
  EXPECT_EQ(v.notes, std::vector<std::string>{"mesh coloured at each vertex by the deviation of the measured points closest to its triangles "
                                              "(their signed RMS; grey: no point measured there); the measured points by their own deviation"});
  std::vector<std::string> captions;
  for (const PictureView& p : v.pictures) {
    captions.push_back(p.caption);
    ASSERT_GT(p.png.size(), 8u);
    EXPECT_EQ(p.png[1], 'P');
  }
  EXPECT_EQ(captions, (std::vector<std::string>{"mesh, iso view, deviation", "mesh, front view, deviation", "mesh, side view, deviation",
                                                "mesh, top view, deviation", "cloud, iso view, deviation"}));
  EXPECT_FALSE(v.mesh_decimated);
  EXPECT_FALSE(v.cloud_subsampled);
}

TEST(HtmlReportView, TheBrowsersLimitsAreKeptAndSaid) {
  HtmlReportInputs in = inputs();
  const TriangleMesh sphere = test::icosphere_mesh(4);  // 5120 triangles
  in.mesh.vertices.positions = sphere.vertices.positions;
  in.mesh.triangles = sphere.triangles;
  in.cloud = test::sample_sphere(3000);
  HtmlReportParams params;
  params.max_browser_triangles = 1000;
  params.max_browser_points = 400;
  params.view_width = 32;
  params.view_height = 24;
  const HtmlReportView v = html_report_view(in, params);
  ASSERT_TRUE(v.mesh);
  EXPECT_TRUE(v.mesh_decimated);
  EXPECT_LE(v.mesh->triangles, 1000u);
  EXPECT_EQ(v.mesh->original_triangles, 5120u);
  EXPECT_EQ(v.mesh->positions.size(), 3 * v.mesh->vertices);
  ASSERT_TRUE(v.cloud);
  EXPECT_TRUE(v.cloud_subsampled);
  EXPECT_EQ(v.cloud->points, 400u);
  EXPECT_EQ(v.cloud->original_points, 3000u);
  ASSERT_EQ(v.notes.size(), 2u);
  EXPECT_TRUE(test::contains(v.notes[0], "mesh decimated from 5120 to "));
  EXPECT_TRUE(test::contains(v.notes[1], "cloud subsampled from 3000 to 400 points"));
  // Without the field "deviation": a plain grey mesh, no legend, pictures without a field.
  EXPECT_FALSE(v.legend);
  EXPECT_EQ(v.mesh->colors[0], 190);
  EXPECT_EQ(v.pictures.back().caption, "cloud, iso view");
}

TEST(HtmlReportView, MalformedRunReportIsAnInputError) {
  HtmlReportInputs in;
  in.run_json = "{\"stages\": [";
  in.origin = "bad.json";
  test::expect_error<InputError>([&] { html_report_view(in); }, "bad.json: not a run report (JSON)");
}

}  // namespace
}  // namespace pointsurf::detail
