// SPDX-License-Identifier: GPL-3.0-or-later
// The HTML report in two phases: the view model (report/detail/html_report_view.h) reads the
// run report and the geometry and decides what is shown; the page
// (report/detail/html_report_page.h) writes HTML around it.
#include "pointsurf/report/html_report.h"

#include <map>

#include <nlohmann/json.hpp>

#include "report/detail/html_report_page.h"
#include "report/detail/html_report_view.h"

namespace pointsurf {

using nlohmann::json;
using detail::find_path;

ReportSources report_sources(const std::string& run_json, const std::string& origin) {
  const json report = detail::parse_run_report(run_json, origin);
  ReportSources s;
  std::map<std::string, std::string> written;  // tag -> the file it was read from or written to
  std::string last_mesh, first_read;
  const json* evaluate = nullptr;
  const json stages = report.value("stages", json::array());
  for (const json& st : stages) {
    const std::string type = st.value("type", "");
    const json params = st.value("parameters", json::object());
    if (type == "read") {
      if (first_read.empty()) first_read = params.value("filename", "");
      written[st.value("tag", "")] = params.value("filename", "");  // a mesh measured as read
    }
    if (type == "write" && st.contains("inputs") && !st["inputs"].empty()) {
      written[st["inputs"][0].get<std::string>()] = params.value("filename", "");
      const json* faces = find_path(st, {"counts", "faces"});
      if (faces && faces->is_number() && faces->get<double>() > 0) last_mesh = params.value("filename", "");
    }
    if (type == "evaluate") evaluate = &st;
  }
  s.mesh_file = last_mesh;
  s.cloud_file = first_read;
  if (evaluate) {
    const std::string mesh_tag = (*evaluate)["inputs"].empty() ? "" : (*evaluate)["inputs"][0].get<std::string>();
    if (written.count(mesh_tag)) s.mesh_file = written[mesh_tag];
    if (written.count(evaluate->value("tag", ""))) {
      s.cloud_file = written[evaluate->value("tag", "")];
      s.cloud_has_deviation = true;
    }
  }
  return s;
}

HtmlReport build_html_report(const HtmlReportInputs& in, const HtmlReportParams& params) {
  const detail::HtmlReportView view = detail::html_report_view(in, params);
  HtmlReport out;
  out.html = detail::render_html_report_page(view);
  out.triangles_shown = view.mesh ? view.mesh->triangles : 0;
  out.points_shown = view.cloud ? view.cloud->points : 0;
  out.mesh_decimated = view.mesh_decimated;
  out.cloud_subsampled = view.cloud_subsampled;
  out.notes = view.notes;
  return out;
}

}  // namespace pointsurf
