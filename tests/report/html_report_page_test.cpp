// SPDX-License-Identifier: GPL-3.0-or-later
// The report's page alone, written from a hand-made view model.
#include "report/detail/html_report_page.h"

#include <cstring>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/files.h"

namespace pointsurf::detail {
namespace {

using nlohmann::json;

HtmlReportView view() {
  HtmlReportView v;
  v.title = "runs/<b>run</b>.json";
  v.summary = {"p.json", "run", "ok", "0.1.0", 0.7349, 45.06, "[mesh.ply]", std::nullopt};
  StageView read;
  read.index = 1;
  read.type = "read";
  read.tag = "in";
  read.chart_label = "1 in";
  read.inputs = "[]";
  read.seconds = 0.0123;
  read.peak_rss_mb = 20.04;
  read.rss_rise_mb = 2.0;
  read.parameters = {{"filename", "scan.ply"}};
  read.counts_and_metrics = {{"points", "2000"}};
  StageView odd;
  odd.index = 2;
  odd.type = "<script>alert(1)</script>";
  odd.tag = "t&g";
  odd.chart_label = "2 t&g";
  odd.inputs = "[in]";
  odd.seconds = 1.5;
  odd.peak_rss_mb = 40.0;
  odd.rss_rise_mb = 19.96;
  odd.parameters = {{"radius/value", "3"}};
  odd.warnings = {"holes <script>x</script>"};
  StageView evaluate;
  evaluate.index = 3;
  evaluate.type = "evaluate";
  evaluate.tag = "evaluate3";
  evaluate.chart_label = "3 evaluate";
  evaluate.inputs = "[t&g, in]";
  evaluate.expanded = true;
  evaluate.counts_and_metrics = {{"deviation/rms", "0.01"}};
  v.stages = {read, odd, evaluate};
  v.deviation.evaluated = true;
  v.deviation.statistics = {{"rms", "0.01"}, {"tolerance", "0.005"}, {"within_tolerance", "0.6"}};
  v.deviation.tolerance = 0.005;
  v.deviation.histogram = DeviationView::Histogram{{-0.02, 0.0, 0.02}, json({100, 1800, 100}), {{255, 0, 0}, {0, 128, 0}, {0, 0, 255}}};
  v.legend = LegendView{-0.03, 0.03, 0.005, std::vector<Rgb>(21, Rgb{0, 128, 0})};
  v.centre = {5e5, 4e6, 100};
  v.radius = 1.5;
  BrowserMesh m;
  m.positions = {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f};
  m.indices = {0, 1, 2};
  m.colors = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  m.vertices = 3;
  m.triangles = 1;
  m.original_triangles = 1;
  v.mesh = m;
  v.pictures = {{"mesh, iso view", {1, 2, 3}}};
  v.warnings = {"stage 2: holes <script>x</script>", "second & last"};
  v.notes = {"mesh coloured by the deviation of the nearest measured point"};
  v.run_report = {{"status", "ok"}, {"pipeline", "</script><b>end</b>"}};
  v.three_js = "var THREE = '</script>';";
  return v;
}

json payload_of(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"pointsurf-data\">";
  const std::size_t a = html.find(open);
  EXPECT_NE(a, std::string::npos);
  const std::size_t b = html.find("</script>", a);
  return json::parse(html.substr(a + open.size(), b - a - open.size()));
}

TEST(HtmlReportPage, EveryStageRowAndNumberAppears) {
  const std::string html = render_html_report_page(view());
  // Seconds to 3 decimals, MiB to 1.
  EXPECT_TRUE(test::contains(html, "<tr><td>1</td><td>read</td><td>[]</td><td>0.012</td><td>20.0</td><td>2.0</td></tr>"));
  EXPECT_TRUE(test::contains(html, "<td>1.500</td><td>40.0</td><td>20.0</td></tr>"));
  EXPECT_TRUE(test::contains(html, "<tr><td>3</td><td>evaluate</td><td>[t&amp;g, in]</td><td>0.000</td><td>0.0</td><td>0.0</td></tr>"));
  EXPECT_TRUE(test::contains(html, "<details class=\"stage\"><summary>1 read (in)</summary>"));
  EXPECT_TRUE(test::contains(html, "<details class=\"stage\" open><summary>3 evaluate (evaluate3)</summary>"));
  EXPECT_TRUE(test::contains(html, "<tr><td>filename</td><td>scan.ply</td></tr>"));
  EXPECT_TRUE(test::contains(html, "<tr><td>deviation/rms</td><td>0.01</td></tr>"));
  // The summary.
  EXPECT_TRUE(test::contains(html, "<td>status</td><td class=\"ok\">ok</td>"));
  EXPECT_TRUE(test::contains(html, "<td>total time</td><td>0.735 s</td>"));
  EXPECT_TRUE(test::contains(html, "<td>peak memory</td><td>45.1 MiB</td>"));
  EXPECT_TRUE(test::contains(html, "<td>outputs</td><td>[mesh.ply]</td>"));
  EXPECT_FALSE(test::contains(html, "class=\"bad\">error"));
  EXPECT_TRUE(test::contains(html, "<li>mesh coloured by the deviation of the nearest measured point</li>"));
  // The deviation table, the picture, the counts of the 3D view.
  EXPECT_TRUE(test::contains(html, "<th>deviation</th><th>value</th></tr></thead><tbody><tr><td>rms</td><td>0.01</td></tr>"
                                   "<tr><td>tolerance</td><td>0.005</td></tr><tr><td>within_tolerance</td><td>0.6</td></tr></tbody>"));
  EXPECT_TRUE(test::contains(html, "<figure><img alt=\"mesh, iso view\" src=\"data:image/png;base64,AQID\"><figcaption>mesh, iso view</figcaption>"));
  EXPECT_TRUE(test::contains(html, "mesh (1 triangles)"));
  EXPECT_TRUE(test::contains(html, "cloud (0 points)"));
  EXPECT_TRUE(test::contains(html, "<li>second &amp; last</li>"));
}

TEST(HtmlReportPage, TextsAreEscaped) {
  const std::string html = render_html_report_page(view());
  EXPECT_FALSE(test::contains(html, "<script>alert"));
  EXPECT_FALSE(test::contains(html, "<script>x"));
  EXPECT_FALSE(test::contains(html, "<b>run"));
  EXPECT_TRUE(test::contains(html, "<td>&lt;script&gt;alert(1)&lt;/script&gt;</td>"));
  EXPECT_TRUE(test::contains(html, "<summary>2 &lt;script&gt;alert(1)&lt;/script&gt; (t&amp;g)</summary>"));
  EXPECT_TRUE(test::contains(html, "<li>holes &lt;script&gt;x&lt;/script&gt;</li>"));
  EXPECT_TRUE(test::contains(html, "<li>stage 2: holes &lt;script&gt;x&lt;/script&gt;</li>"));
  EXPECT_TRUE(test::contains(html, "<title>pointsurf report: runs/&lt;b&gt;run&lt;/b&gt;.json</title>"));
  // Scripts cannot end their element early: the inlined library and the payload write "<\/".
  EXPECT_TRUE(test::contains(html, "var THREE = '<\\/script>';"));
  EXPECT_FALSE(test::contains(html, "</script><b>end"));
  EXPECT_EQ(payload_of(html)["report"]["pipeline"], "</script><b>end</b>");
}

TEST(HtmlReportPage, ThePayloadCarriesTheViewsValues) {
  const HtmlReportView v = view();
  const json p = payload_of(render_html_report_page(v));
  EXPECT_EQ(p["centre"], json({5e5, 4e6, 100.0}));
  EXPECT_DOUBLE_EQ(p["radius"].get<double>(), 1.5);
  // base64 of the typed arrays, little endian: 3 float32 vertices, one uint32 triangle.
  EXPECT_EQ(p["mesh"]["colors"], "AQIDBAUGBwgJ");
  EXPECT_EQ(p["mesh"]["indices"], "AAAAAAEAAAACAAAA");
  EXPECT_EQ(p["mesh"]["positions"].get<std::string>().size(), 48u);  // 36 bytes
  EXPECT_EQ(p["mesh"]["triangles"], 1);
  EXPECT_FALSE(p.contains("cloud"));
  EXPECT_EQ(p["legend"]["tolerance"], 0.005);
  EXPECT_EQ(p["legend"]["stops"].size(), 21u);
  EXPECT_EQ(p["legend"]["stops"][0], "#008000");
  EXPECT_EQ(p["histogram"]["counts"], json({100, 1800, 100}));
  EXPECT_EQ(p["histogram"]["colors"], json({"#ff0000", "#008000", "#0000ff"}));
  ASSERT_EQ(p["stages"].size(), 3u);
  EXPECT_EQ(p["stages"][1]["label"], "2 t&g");
  EXPECT_DOUBLE_EQ(p["stages"][1]["seconds"].get<double>(), 1.5);
  EXPECT_EQ(p["notes"], json(v.notes));
  EXPECT_EQ(p["report"], v.run_report);
}

TEST(HtmlReportPage, AnEmptyRunSaysWhatIsMissing) {
  HtmlReportView v;
  v.summary.status = "failed";
  v.summary.error = "stage 2: no <triangles>";
  const std::string html = render_html_report_page(v);
  EXPECT_TRUE(test::contains(html, "<td>status</td><td class=\"bad\">failed</td>"));
  EXPECT_TRUE(test::contains(html, "<p class=\"bad\">error: stage 2: no &lt;triangles&gt;</p>"));
  EXPECT_TRUE(test::contains(html, "<p>No geometry was written by this run.</p>"));
  EXPECT_TRUE(test::contains(html, "<p>This run has no evaluate stage.</p>"));
  EXPECT_TRUE(test::contains(html, "<section id=\"warnings\"><h2>Warnings</h2><p>None.</p></section>"));
  const json p = payload_of(html);
  EXPECT_FALSE(p.contains("mesh"));
  EXPECT_FALSE(p.contains("legend"));
  EXPECT_FALSE(p.contains("histogram"));
  EXPECT_EQ(p["stages"], json::array());
}

}  // namespace
}  // namespace pointsurf::detail
