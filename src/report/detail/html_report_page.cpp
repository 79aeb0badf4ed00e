// SPDX-License-Identifier: GPL-3.0-or-later
// The page. Tables are written here as static HTML (they read without JavaScript); the 3D view
// and the charts are built in the page from one JSON payload, with the geometry as base64
// little-endian typed arrays (float32 positions about the centre, uint32 indices, uint8
// colours), so a million-triangle mesh costs 4/3 of its bytes and no parsing of numbers.
#include "report/detail/html_report_page.h"

#include <map>

#include <fmt/format.h>

#include "report/detail/page.h"

namespace pointsurf::detail {
namespace {

using nlohmann::json;

std::string base64(const void* data, std::size_t size) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* b = static_cast<const std::uint8_t*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const std::uint32_t v = std::uint32_t(b[i]) << 16 | (i + 1 < size ? std::uint32_t(b[i + 1]) << 8 : 0u) | (i + 2 < size ? b[i + 2] : 0u);
    out += table[(v >> 18) & 63];
    out += table[(v >> 12) & 63];
    out += i + 1 < size ? table[(v >> 6) & 63] : '=';
    out += i + 2 < size ? table[v & 63] : '=';
  }
  return out;
}

template <class T>
std::string base64(const std::vector<T>& v) {
  return base64(v.data(), v.size() * sizeof(T));
}

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string hex(const Rgb& c) { return fmt::format("#{:02x}{:02x}{:02x}", c[0], c[1], c[2]); }

json hex_list(const std::vector<Rgb>& colors) {
  json out = json::array();
  for (const Rgb& c : colors) out.push_back(hex(c));
  return out;
}

std::string table(const TextRows& rows, const char* head_key, const char* head_value) {
  std::string out = fmt::format("<table><thead><tr><th>{}</th><th>{}</th></tr></thead><tbody>", head_key, head_value);
  for (const auto& [k, v] : rows) out += fmt::format("<tr><td>{}</td><td>{}</td></tr>", escape(k), escape(v));
  return out + "</tbody></table>";
}

std::string list_items(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& i : items) out += "<li>" + escape(i) + "</li>";
  return out;
}

// What the page's script reads: the geometry, the legend, the histogram, the stage chart, the
// notes and the run report itself.
json payload(const HtmlReportView& view) {
  json p;
  p["centre"] = {view.centre[0], view.centre[1], view.centre[2]};
  p["radius"] = view.radius;
  if (const auto& m = view.mesh)
    p["mesh"] = {{"positions", base64(m->positions)}, {"indices", base64(m->indices)}, {"colors", base64(m->colors)},
                 {"vertices", m->vertices},           {"triangles", m->triangles},     {"original_triangles", m->original_triangles}};
  if (const auto& c = view.cloud)
    p["cloud"] = {{"positions", base64(c->positions)}, {"colors", base64(c->colors)}, {"points", c->points}, {"original_points", c->original_points}};
  if (const auto& l = view.legend)
    p["legend"] = {{"field", "deviation"}, {"min", l->min},          {"max", l->max},
                   {"tolerance", l->tolerance}, {"stops", hex_list(l->stops)}, {"under", hex_list({l->under})[0]},
                   {"over", hex_list({l->over})[0]}};
  if (const auto& h = view.deviation.histogram)
    p["histogram"] = {{"centres", h->centres}, {"counts", h->counts}, {"colors", hex_list(h->colors)}};
  json stages = json::array();
  for (const StageView& st : view.stages)
    stages.push_back({{"label", st.chart_label}, {"seconds", st.seconds}, {"peak_rss_mb", st.peak_rss_mb}, {"rss_rise_mb", st.rss_rise_mb}});
  p["stages"] = stages;
  p["notes"] = view.notes;
  p["report"] = view.run_report;
  return p;
}

std::string summary_table(const RunSummaryView& s) {
  std::string out = fmt::format(
      "<table class=\"kv\"><tbody><tr><td>pipeline</td><td>{}</td></tr><tr><td>command</td><td>{}</td></tr><tr><td>status</td><td class=\"{}\">{}</td></tr>"
      "<tr><td>total time</td><td>{:.3f} s</td></tr><tr><td>peak memory</td><td>{:.1f} MiB</td></tr><tr><td>pointsurf</td><td>{}</td></tr>"
      "<tr><td>outputs</td><td>{}</td></tr></tbody></table>",
      escape(s.pipeline), escape(s.command), s.status == "ok" ? "ok" : "bad", escape(s.status), s.total_seconds, s.peak_rss_mb, escape(s.version),
      escape(s.outputs));
  if (s.error) out += fmt::format("<p class=\"bad\">error: {}</p>", escape(*s.error));
  return out;
}

std::string picture_figures(const std::vector<PictureView>& pictures) {
  std::string out;
  for (const PictureView& p : pictures)
    out += fmt::format("<figure><img alt=\"{0}\" src=\"data:image/png;base64,{1}\"><figcaption>{0}</figcaption></figure>", escape(p.caption),
                       base64(p.png));
  return out;
}

std::string stage_row(const StageView& st) {
  return fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3f}</td><td>{:.1f}</td><td>{:.1f}</td></tr>", st.index, escape(st.type),
                     escape(st.inputs), st.seconds, st.peak_rss_mb, st.rss_rise_mb);
}

std::string stage_details(const StageView& st) {
  const std::string warnings = list_items(st.warnings);
  return fmt::format("<details class=\"stage\"{}><summary>{}</summary><div class=\"two\"><div><h4>Parameters</h4>{}</div><div><h4>Counts and "
                     "metrics</h4>{}</div></div>{}</details>",
                     st.expanded ? " open" : "", escape(fmt::format("{} {} ({})", st.index, st.type, st.tag)),
                     table(st.parameters, "parameter", "value"), table(st.counts_and_metrics, "key", "value"),
                     warnings.empty() ? "" : "<h4>Warnings</h4><ul class=\"warn\">" + warnings + "</ul>");
}

}  // namespace

std::string render_html_report_page(const HtmlReportView& view) {
  std::string stage_rows, details;
  for (const StageView& st : view.stages) {
    stage_rows += stage_row(st);
    details += stage_details(st);
  }
  const std::string pictures = picture_figures(view.pictures);
  const std::string warnings = list_items(view.warnings);

  std::string data = payload(view).dump();
  // Inside <script>, "</" would end the element: JSON allows "<\/".
  for (std::size_t at = 0; (at = data.find("</", at)) != std::string::npos; at += 3) data.replace(at, 2, "<\\/");

  const std::map<std::string, std::string> slots = {
      {"TITLE", escape(view.title)},
      {"SUMMARY", summary_table(view.summary)},
      {"NOTES", list_items(view.notes)},
      {"PICTURES", pictures.empty() ? "<p>No geometry was written by this run.</p>" : pictures},
      {"DEVIATION_TABLE", view.deviation.evaluated ? table(view.deviation.statistics, "deviation", "value") : "<p>This run has no evaluate stage.</p>"},
      {"STAGE_ROWS", stage_rows},
      {"STAGE_DETAILS", details},
      {"WARNINGS", warnings.empty() ? "<p>None.</p>" : "<ul class=\"warn\">" + warnings + "</ul>"},
      {"MESH_TRIANGLES", fmt::format("{}", view.mesh ? view.mesh->triangles : 0)},
      {"CLOUD_POINTS", fmt::format("{}", view.cloud ? view.cloud->points : 0)},
      {"THREE_JS", view.three_js},
      {"ORBIT_JS", view.orbit_controls_js},
      {"CHART_JS", view.chart_js},
      {"PAYLOAD", data},
  };
  return fill_page(slots);
}

}  // namespace pointsurf::detail
