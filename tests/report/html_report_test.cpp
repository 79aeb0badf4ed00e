// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/report/html_report.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/mesh_shapes.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using nlohmann::json;

// A run report as pointsurf run writes it: read, reconstruct, write the mesh, evaluate, write
// the deviation cloud.
std::string run_json() {
  json stages = json::array();
  stages.push_back({{"index", 1}, {"type", "read"}, {"tag", "in"}, {"inputs", json::array()}, {"parameters", {{"filename", "scan.ply"}}},
                    {"counts", {{"points", 2000}}}, {"metrics", json::object()}, {"warnings", json::array()}, {"seconds", 0.01},
                    {"peak_rss_mb", 20.0}, {"rss_rise_mb", 2.0}});
  stages.push_back({{"index", 2}, {"type", "reconstruct"}, {"tag", "mesh"}, {"inputs", {"in"}}, {"parameters", {{"method", "ball-pivot"}, {"radius", 0.1}}},
                    {"counts", {{"triangles", 5120}}}, {"metrics", json::object()}, {"warnings", {"3 holes left <open>"}}, {"seconds", 0.5},
                    {"peak_rss_mb", 40.0}, {"rss_rise_mb", 20.0}});
  stages.push_back({{"index", 3}, {"type", "write"}, {"tag", "write3"}, {"inputs", {"mesh"}}, {"parameters", {{"filename", "mesh.ply"}}},
                    {"counts", {{"points", 2562}, {"faces", 5120}}}, {"metrics", json::object()}, {"warnings", json::array()}, {"seconds", 0.01},
                    {"peak_rss_mb", 40.0}, {"rss_rise_mb", 0.0}});
  json deviation = {{"count", 2000}, {"max_positive", 0.02}, {"max_negative", -0.03}, {"rms", 0.01}, {"tolerance", 0.005},
                    {"within_tolerance", 0.6}, {"histogram", {{"edges", {-0.03, -0.01, 0.01, 0.03}}, {"counts", {100, 1800, 100}}}}};
  stages.push_back({{"index", 4}, {"type", "evaluate"}, {"tag", "dev"}, {"inputs", {"mesh", "in"}}, {"parameters", {{"tolerance", 0.005}}},
                    {"counts", json::object()}, {"metrics", {{"deviation", deviation}}}, {"warnings", json::array()}, {"seconds", 0.2},
                    {"peak_rss_mb", 45.0}, {"rss_rise_mb", 5.0}});
  stages.push_back({{"index", 5}, {"type", "write"}, {"tag", "write5"}, {"inputs", {"dev"}}, {"parameters", {{"filename", "deviation.ply"}}},
                    {"counts", {{"points", 2000}, {"faces", 0}}}, {"metrics", json::object()}, {"warnings", json::array()}, {"seconds", 0.01},
                    {"peak_rss_mb", 45.0}, {"rss_rise_mb", 0.0}});
  json r = {{"command", "run"}, {"version", "0.1.0"}, {"pipeline", "p.json"}, {"status", "ok"}, {"stages", stages},
            {"outputs", {"mesh.ply", "deviation.ply"}}, {"warnings", {"stage 2 (reconstruct): 3 holes left <open>"}}, {"total_seconds", 0.73},
            {"peak_rss_mb", 45.0}};
  return r.dump(2);
}

HtmlReportInputs inputs() {
  HtmlReportInputs in;
  in.run_json = run_json();
  in.origin = "run.json";
  const TriangleMesh sphere = test::icosphere_mesh(4, 1.0, Vector3d(5e5, 4e6, 100));
  in.mesh.vertices.positions = sphere.vertices.positions;
  in.mesh.triangles = sphere.triangles;
  in.cloud = test::sample_sphere(2000, 1.01, Vector3d(5e5, 4e6, 100));
  ScalarField& d = in.cloud.fields.add("deviation", in.cloud.size());
  for (std::size_t i = 0; i < d.values.size(); ++i) d.values[i] = 0.01 * ((in.cloud.positions[i].z() - 100) > 0 ? 1 : -1);
  in.three_js = "var THREE_STUB = '</script>';";
  in.orbit_controls_js = "/* orbit */";
  in.chart_js = "/* chart */";
  return in;
}

json payload_of(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"pointsurf-data\">";
  const std::size_t a = html.find(open);
  EXPECT_NE(a, std::string::npos);
  const std::size_t b = html.find("</script>", a);
  return json::parse(html.substr(a + open.size(), b - a - open.size()));
}

std::vector<std::uint8_t> unbase64(const std::string& s) {
  std::vector<std::uint8_t> out;
  std::uint32_t buffer = 0;
  int bits = 0;
  for (char c : s) {
    const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* at = std::strchr(table, c);
    if (c == '=' || at == nullptr) break;
    buffer = buffer << 6 | std::uint32_t(at - table);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(std::uint8_t(buffer >> bits));
    }
  }
  return out;
}

TEST(HtmlReport, HasEverySectionAndAValidPayload) {
  const HtmlReportInputs in = inputs();
  const HtmlReport r = build_html_report(in);
  for (const char* id : {"id=\"summary\"", "id=\"view3d\"", "id=\"pictures\"", "id=\"deviation\"", "id=\"stages\"", "id=\"details\"",
                         "id=\"warnings\"", "id=\"c3d\"", "id=\"histogram\"", "id=\"time-chart\"", "id=\"memory-chart\"", "id=\"show-cloud\""})
    EXPECT_TRUE(test::contains(r.html, id)) << id;
  // The libraries are inlined, with "</script" made harmless; nothing is fetched.
  EXPECT_TRUE(test::contains(r.html, "var THREE_STUB = '<\\/script>';"));
  EXPECT_FALSE(test::contains(r.html, "src=\"http"));
  // Tables: parameters, metrics, warnings, escaped.
  EXPECT_TRUE(test::contains(r.html, "<td>ball-pivot</td>"));
  EXPECT_TRUE(test::contains(r.html, "<td>max_negative</td><td>-0.03</td>"));
  EXPECT_TRUE(test::contains(r.html, "3 holes left &lt;open&gt;"));
  // Five PNG views: four of the mesh, one of the cloud.
  std::size_t pictures = 0;
  for (std::size_t at = 0; (at = r.html.find("data:image/png;base64,", at)) != std::string::npos; ++at) ++pictures;
  EXPECT_EQ(pictures, 5u);

  const json p = payload_of(r.html);
  EXPECT_EQ(p["mesh"]["triangles"].get<std::size_t>(), in.mesh.triangles.size());
  EXPECT_EQ(unbase64(p["mesh"]["positions"].get<std::string>()).size(), 12 * in.mesh.vertices.size());
  EXPECT_EQ(unbase64(p["mesh"]["indices"].get<std::string>()).size(), 12 * in.mesh.triangles.size());
  EXPECT_EQ(unbase64(p["cloud"]["colors"].get<std::string>()).size(), 3 * in.cloud.size());
  // Positions are about the centre: float32 keeps them although the data sit at 4e6 m.
  const std::vector<std::uint8_t> pos = unbase64(p["mesh"]["positions"].get<std::string>());
  float first[3];
  std::memcpy(first, pos.data(), sizeof first);
  EXPECT_NEAR(first[0], in.mesh.vertices.positions[0].x() - p["centre"][0].get<double>(), 1e-6);
  EXPECT_NEAR(p["centre"][1].get<double>(), 4e6, 0.1);
  EXPECT_EQ(p["histogram"]["counts"], json({100, 1800, 100}));
  EXPECT_EQ(p["stages"].size(), 5u);
  EXPECT_DOUBLE_EQ(p["legend"]["tolerance"].get<double>(), 0.005);
  EXPECT_EQ(p["report"]["status"], "ok");
  EXPECT_FALSE(r.mesh_decimated);
  EXPECT_FALSE(r.cloud_subsampled);
}

TEST(HtmlReport, DecimatesForTheBrowserAboveTheLimits) {
  HtmlReportInputs in = inputs();
  const TriangleMesh big = test::icosphere_mesh(6);  // 81,920 triangles
  in.mesh.vertices.positions = big.vertices.positions;
  in.mesh.triangles = big.triangles;
  in.cloud = test::sample_sphere(30000);
  HtmlReportParams params;
  params.max_browser_triangles = 10000;
  params.max_browser_points = 5000;
  const HtmlReport r = build_html_report(in, params);
  EXPECT_TRUE(r.mesh_decimated);
  EXPECT_LE(r.triangles_shown, 10000u);
  EXPECT_GT(r.triangles_shown, 2500u);
  EXPECT_TRUE(r.cloud_subsampled);
  EXPECT_EQ(r.points_shown, 5000u);
  const json p = payload_of(r.html);
  EXPECT_EQ(p["mesh"]["original_triangles"].get<std::size_t>(), big.triangles.size());
  EXPECT_EQ(p["cloud"]["points"].get<std::size_t>(), 5000u);
  // Indices stay within the decimated vertices.
  const std::vector<std::uint8_t> idx = unbase64(p["mesh"]["indices"].get<std::string>());
  const std::size_t vertices = p["mesh"]["vertices"].get<std::size_t>();
  for (std::size_t i = 0; i + 4 <= idx.size(); i += 4) {
    std::uint32_t v;
    std::memcpy(&v, idx.data() + i, 4);
    ASSERT_LT(v, vertices);
  }
  bool noted = false;
  for (const std::string& n : r.notes) noted |= test::contains(n, "decimated from 81920");
  EXPECT_TRUE(noted);
}

TEST(HtmlReport, SourcesAreTheEvaluatedMeshAndTheDeviationCloud) {
  const ReportSources s = report_sources(run_json(), "run.json");
  EXPECT_EQ(s.mesh_file, "mesh.ply");
  EXPECT_EQ(s.cloud_file, "deviation.ply");
  EXPECT_TRUE(s.cloud_has_deviation);
  // Without evaluate: the last mesh written and the cloud as read.
  json r = json::parse(run_json());
  r["stages"].erase(3);
  const ReportSources t = report_sources(r.dump(), "run.json");
  EXPECT_EQ(t.mesh_file, "mesh.ply");
  EXPECT_EQ(t.cloud_file, "scan.ply");
  EXPECT_FALSE(t.cloud_has_deviation);
}

TEST(HtmlReport, MalformedRunReportIsAnInputError) {
  test::expect_error<InputError>([] { report_sources("{\"stages\": [", "bad.json"); }, "bad.json: not a run report (JSON)");
  HtmlReportInputs in;
  in.run_json = "nope";
  in.origin = "x.json";
  test::expect_error<InputError>([&] { build_html_report(in); }, "x.json: not a run report");
}

}  // namespace
}  // namespace pointsurf
