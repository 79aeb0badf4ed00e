// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The HTML report's view model: everything the page shows, read from a run's report, its mesh
// and cloud, as values and texts, with no HTML in it. Building it decides what is shown (which
// evaluate stage gives the deviation and which of its keys, the colours, what the 3D view can
// hold, the PNG views); html_report_page.h only writes the page around it. Internal: the view
// holds the run report as JSON, which the page embeds for its script.
#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "pointsurf/report/html_report.h"

namespace pointsurf::detail {

using Rgb = std::array<std::uint8_t, 3>;
using TextRows = std::vector<std::pair<std::string, std::string>>;  // (key, value text), in order shown

/// The run as a whole: the summary table.
struct RunSummaryView {
  std::string pipeline, command, status, version;  // as in the run report ("?" for a missing status)
  double total_seconds = 0.0;
  double peak_rss_mb = 0.0;                 // MiB
  std::string outputs;                      // the files written, as value text ("[a.ply, b.ply]")
  std::optional<std::string> error;         // the error message when the report has an "error"
};

/// One stage: its row in the stage table and the chart, and its details.
struct StageView {
  int index = 0;
  std::string type, tag;
  std::string chart_label;                  // "7 ball": the tag, or the type where the tag is the default "<type><index>"
  std::string inputs;                       // value text of the input tags
  double seconds = 0.0, peak_rss_mb = 0.0, rss_rise_mb = 0.0;  // MiB
  TextRows parameters;                      // nested keys joined by "/"
  TextRows counts_and_metrics;
  std::vector<std::string> warnings;
  bool expanded = false;                    // an evaluate stage: its details shown open
};

/// Evaluate's deviation: the last evaluate stage's "metrics/deviation" block.
struct DeviationView {
  bool evaluated = false;                   // there is such a block (its table is shown, maybe empty)
  TextRows statistics;                      // the headline values of DeviationStats::results(): those present
  double tolerance = 0.0;                   // field units; 0 when no evaluate stage gives one
  struct Histogram {
    std::vector<double> centres;            // of the bins, field units
    nlohmann::json counts;                  // points per bin, as in the run report
    std::vector<Rgb> colors;                // of the bins' centres on the map's scale
  };
  std::optional<Histogram> histogram;
};

/// The colour map's legend: only when the cloud has the field "deviation".
struct LegendView {
  double min = 0.0, max = 0.0, tolerance = 0.0;  // field units
  std::vector<Rgb> stops;                   // 21 colours from min to max
  Rgb under{}, over{};                      // the colours of values below min and above max
};

/// The geometry of the 3D view, about `centre`: float32 positions (x, y, z per vertex), uint8
/// colours (r, g, b per vertex).
struct BrowserMesh {
  std::vector<float> positions;
  std::vector<std::uint32_t> indices;       // 3 per triangle
  std::vector<std::uint8_t> colors;
  std::size_t vertices = 0, triangles = 0, original_triangles = 0;
};
struct BrowserCloud {
  std::vector<float> positions;
  std::vector<std::uint8_t> colors;
  std::size_t points = 0, original_points = 0;
};

/// A PNG view from pointsurf's renderer.
struct PictureView {
  std::string caption;                      // "mesh, iso view, deviation"
  std::vector<std::uint8_t> png;            // the encoded file
};

struct HtmlReportView {
  std::string title;                        // the run report's file name
  RunSummaryView summary;
  std::vector<StageView> stages;            // in run order
  DeviationView deviation;
  std::optional<LegendView> legend;
  std::array<double, 3> centre{};           // of everything in the 3D view, cloud units
  double radius = 0.0;                      // half the bounding box's diagonal
  std::optional<BrowserMesh> mesh;
  std::optional<BrowserCloud> cloud;
  std::vector<PictureView> pictures;        // mesh iso, front, side, top; cloud iso (those with geometry)
  std::vector<std::string> warnings;        // of the whole run
  std::vector<std::string> notes;           // what the 3D view shows how (colouring, decimation)
  bool mesh_decimated = false, cloud_subsampled = false;
  nlohmann::json run_report;                // embedded as read, for the page's script
  std::string three_js, orbit_controls_js, chart_js;  // inlined as given
};

/// The view of a run: reads the run report (InputError "ORIGIN: not a run report (JSON): ..."
/// when it is not JSON), colours the mesh by the deviation of the nearest point of a cloud
/// with the field "deviation", decimates and subsamples for the browser above params' limits,
/// and renders the PNG views (params' size). Thread-safe.
HtmlReportView html_report_view(const HtmlReportInputs& inputs, const HtmlReportParams& params = {});

/// The run report's JSON; InputError "ORIGIN: not a run report (JSON): ..." when it is not JSON.
nlohmann::json parse_run_report(const std::string& text, const std::string& origin);

/// The member at keys below j (j["a"]["b"]), or nullptr where one is missing or not an object.
const nlohmann::json* find_path(const nlohmann::json& j, std::initializer_list<const char*> keys);

}  // namespace pointsurf::detail
