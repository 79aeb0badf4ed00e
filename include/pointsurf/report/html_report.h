// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The HTML report of a run: one self-contained file that opens offline, with an interactive 3D
// view (three.js, inlined), the deviation histogram and per-stage time and memory (Chart.js,
// inlined), tables of every metric and parameter, and PNG views from pointsurf's renderer.
// The library builds the text; the caller reads the files (the run report, its outputs, the
// JavaScript libraries) and writes the result.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

/// The files of a run the report shows, found in its report (JSON text of report_json):
/// `mesh_file`, the mesh the last evaluate stage measured (the file it was written to or read
/// from; else the last mesh written; "" when none) and `cloud_file`, the cloud with the field "deviation" that evaluate
/// wrote (else the first file read). Throws InputError "ORIGIN: ..." for malformed JSON.
struct ReportSources {
  std::string mesh_file, cloud_file;
  bool cloud_has_deviation = false;  // cloud_file was written by evaluate
};
ReportSources report_sources(const std::string& run_json, const std::string& origin);

struct HtmlReportInputs {
  std::string run_json;                    // the run report (report_json's text)
  std::string origin;                      // its file name, for messages and the page's title
  TriangleMesh mesh;                       // no triangles: no mesh
  PointCloud cloud;                        // the cloud (with "deviation" when evaluated); may be empty
  std::string three_js, orbit_controls_js, chart_js;  // library sources, inlined as given
};

struct HtmlReportParams {
  std::size_t max_browser_triangles = 400000;  // above: the 3D view's mesh is decimated by vertex clustering
  std::size_t max_browser_points = 250000;     // above: the 3D view's cloud is a seeded random subset
  int view_width = 640, view_height = 480;     // PNG views, pixels
  std::uint64_t seed = 1;
};

struct HtmlReport {
  std::string html;
  std::size_t triangles_shown = 0, points_shown = 0;  // in the 3D view
  bool mesh_decimated = false, cloud_subsampled = false;
  std::vector<std::string> notes;  // what was shown how (decimation, colouring)
};

/// Builds the page. The mesh is coloured by the deviation of the nearest cloud point when the
/// cloud has the field "deviation" (the diverging map of the PNG views, with evaluate's
/// tolerance as the green band). Throws InputError for a run report that is not JSON.
/// Thread-safe.
HtmlReport build_html_report(const HtmlReportInputs& inputs, const HtmlReportParams& params = {});

}  // namespace pointsurf
