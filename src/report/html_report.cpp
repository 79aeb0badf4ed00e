// SPDX-License-Identifier: GPL-3.0-or-later
// The HTML report. Tables are written here as static HTML (they read without JavaScript); the
// 3D view and the charts are built in the page from one JSON payload, with the geometry as
// base64 little-endian typed arrays (float32 positions about the centre, uint32 indices,
// uint8 colours), so a million-triangle mesh costs 4/3 of its bytes and no parsing of numbers.
#include "pointsurf/report/html_report.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>
#include <random>
#include <unordered_map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "pointsurf/render/render_scene.h"
#include "pointsurf/spatial/kd_tree.h"
#include "report/detail/page.h"

namespace pointsurf {
namespace {

using nlohmann::json;

nlohmann::json parse(const std::string& text, const std::string& origin) {
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}: not a run report (JSON): {}", origin, e.what()));
  }
}

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

std::string hex(const std::array<std::uint8_t, 3>& c) { return fmt::format("#{:02x}{:02x}{:02x}", c[0], c[1], c[2]); }

// A metric's value as table text: numbers in 6 significant digits, long lists summarised.
std::string value_text(const json& v) {
  if (v.is_null()) return "n/a";
  if (v.is_number_float()) return fmt::format("{:.6g}", v.get<double>());
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array() && v.size() > 8) {
    double lo = 1e300, hi = -1e300;
    for (const json& x : v)
      if (x.is_number()) {
        lo = std::min(lo, x.get<double>());
        hi = std::max(hi, x.get<double>());
      }
    return lo <= hi ? fmt::format("[{} values, {:.4g} .. {:.4g}]", v.size(), lo, hi) : fmt::format("[{} values]", v.size());
  }
  if (v.is_array()) {
    std::string out;
    for (const json& x : v) out += (out.empty() ? "" : ", ") + value_text(x);
    return "[" + out + "]";
  }
  return v.dump();
}

void flatten(const json& v, const std::string& prefix, std::vector<std::pair<std::string, std::string>>& out) {
  if (v.is_object()) {
    for (auto it = v.begin(); it != v.end(); ++it) flatten(it.value(), prefix.empty() ? it.key() : prefix + "/" + it.key(), out);
    return;
  }
  out.emplace_back(prefix, value_text(v));
}

std::string table(const std::vector<std::pair<std::string, std::string>>& rows, const char* head_key, const char* head_value) {
  std::string out = fmt::format("<table><thead><tr><th>{}</th><th>{}</th></tr></thead><tbody>", head_key, head_value);
  for (const auto& [k, v] : rows) out += fmt::format("<tr><td>{}</td><td>{}</td></tr>", escape(k), escape(v));
  return out + "</tbody></table>";
}

// Vertex clustering on a grid: vertices in one cell merge (positions and values averaged),
// faces that collapse are dropped. The cell follows from the area: a surface cut into cells of
// side h keeps about 2 area / h^2 triangles.
void decimate(std::vector<Vector3d>& vertices, std::vector<double>& values, std::vector<Triangle>& triangles, std::size_t target) {
  double area = 0.0;
  for (const Triangle& t : triangles)
    area += 0.5 * (vertices[std::size_t(t[1])] - vertices[std::size_t(t[0])]).cross(vertices[std::size_t(t[2])] - vertices[std::size_t(t[0])]).norm();
  BoundingBox box;
  for (const Vector3d& v : vertices) box.extend(v);
  double cell = std::sqrt(2.0 * area / double(target));
  for (int attempt = 0; attempt < 8; ++attempt, cell *= 1.3) {
    std::unordered_map<std::uint64_t, std::int32_t> index;
    std::vector<std::int32_t> map(vertices.size());
    std::vector<Vector3d> sum;
    std::vector<double> vsum;
    std::vector<int> count;
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      const Vector3d q = (vertices[i] - box.min) / cell;
      const std::uint64_t key = (std::uint64_t(q.x()) & 0x1FFFFF) | (std::uint64_t(q.y()) & 0x1FFFFF) << 21 | (std::uint64_t(q.z()) & 0x1FFFFF) << 42;
      auto [it, fresh] = index.emplace(key, std::int32_t(sum.size()));
      if (fresh) {
        sum.push_back(Vector3d::Zero());
        vsum.push_back(0.0);
        count.push_back(0);
      }
      map[i] = it->second;
      sum[std::size_t(it->second)] += vertices[i];
      if (!values.empty()) vsum[std::size_t(it->second)] += values[i];
      ++count[std::size_t(it->second)];
    }
    std::vector<Triangle> kept;
    for (const Triangle& t : triangles) {
      const Triangle m(map[std::size_t(t[0])], map[std::size_t(t[1])], map[std::size_t(t[2])]);
      if (m[0] != m[1] && m[1] != m[2] && m[0] != m[2]) kept.push_back(m);
    }
    if (kept.size() > target && attempt + 1 < 8) continue;
    for (std::size_t c = 0; c < sum.size(); ++c) {
      sum[c] /= double(count[c]);
      vsum[c] /= double(count[c]);
    }
    vertices = std::move(sum);
    if (!values.empty()) values = std::move(vsum);
    triangles = std::move(kept);
    return;
  }
}

std::string png_tag(const RenderResult& r, const std::string& caption) {
  const std::vector<std::uint8_t> png = encode_png(r.image);
  return fmt::format("<figure><img alt=\"{0}\" src=\"data:image/png;base64,{1}\"><figcaption>{0}</figcaption></figure>", escape(caption),
                     base64(png));
}

const json* find_path(const json& j, std::initializer_list<const char*> keys) {
  const json* at = &j;
  for (const char* k : keys) {
    if (!at->is_object() || !at->contains(k)) return nullptr;
    at = &(*at)[k];
  }
  return at;
}

}  // namespace

ReportSources report_sources(const std::string& run_json, const std::string& origin) {
  const json report = parse(run_json, origin);
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
  const json report = parse(in.run_json, in.origin);
  HtmlReport out;
  const json stages = report.value("stages", json::array());

  // The deviation scale: evaluate's tolerance as the band.
  const ScalarField* deviation = in.cloud.fields.find("deviation");
  double tolerance = 0.0;
  const json* hist = nullptr;
  const json* dev_block = nullptr;
  for (const json& st : stages)
    if (st.value("type", "") == "evaluate") {
      dev_block = find_path(st, {"metrics", "deviation"});
      hist = find_path(st, {"metrics", "deviation", "histogram"});
      if (const json* t = find_path(st, {"metrics", "deviation", "tolerance"}); t && t->is_number()) tolerance = t->get<double>();
    }
  ColorScale scale;
  if (deviation) {
    scale = default_color_scale(deviation->values, "deviation");
    scale.tolerance = tolerance;
  }

  // Geometry for the browser, about the centre of everything shown.
  const bool has_mesh = !in.mesh_triangles.empty();
  BoundingBox box;
  for (const Vector3d& p : in.mesh_vertices.positions) box.extend(p);
  for (const Vector3d& p : in.cloud.positions) box.extend(p);
  const Vector3d centre = box.center();
  json payload;
  payload["centre"] = {centre.x(), centre.y(), centre.z()};
  payload["radius"] = 0.5 * box.diagonal();

  std::vector<double> mesh_values;
  if (has_mesh && deviation) {
    // Each vertex shows the deviation of its nearest measured point.
    const KdTree tree(in.cloud.positions);
    std::vector<Neighbor> nn;
    mesh_values.resize(in.mesh_vertices.size());
    for (std::size_t i = 0; i < mesh_values.size(); ++i) {
      tree.knn(in.mesh_vertices.positions[i], 1, nn);
      mesh_values[i] = nn.empty() ? 0.0 : deviation->values[nn.front().index];
    }
    out.notes.push_back("mesh coloured by the deviation of the nearest measured point");
  }
  if (has_mesh) {
    std::vector<Vector3d> v = in.mesh_vertices.positions;
    std::vector<double> values = mesh_values;
    std::vector<Triangle> t = in.mesh_triangles;
    if (t.size() > params.max_browser_triangles) {
      decimate(v, values, t, params.max_browser_triangles);
      out.mesh_decimated = true;
      out.notes.push_back(fmt::format("3D view: mesh decimated from {} to {} triangles (vertex clustering; the limit is {})",
                                      in.mesh_triangles.size(), t.size(), params.max_browser_triangles));
    }
    std::vector<float> pos;
    std::vector<std::uint32_t> idx;
    std::vector<std::uint8_t> col;
    for (const Vector3d& p : v)
      for (int k = 0; k < 3; ++k) pos.push_back(float(p[k] - centre[k]));
    for (const Triangle& tri : t)
      for (int k = 0; k < 3; ++k) idx.push_back(std::uint32_t(tri[k]));
    for (std::size_t i = 0; i < v.size(); ++i) {
      const auto c = values.empty() ? std::array<std::uint8_t, 3>{190, 196, 206} : scale.color(values[i]);
      col.insert(col.end(), c.begin(), c.end());
    }
    payload["mesh"] = {{"positions", base64(pos)}, {"indices", base64(idx)}, {"colors", base64(col)},
                       {"vertices", v.size()},     {"triangles", t.size()}, {"original_triangles", in.mesh_triangles.size()}};
    out.triangles_shown = t.size();
  }
  if (!in.cloud.empty()) {
    std::vector<std::size_t> keep(in.cloud.size());
    std::iota(keep.begin(), keep.end(), std::size_t(0));
    if (keep.size() > params.max_browser_points) {
      std::mt19937_64 rng(params.seed);
      for (std::size_t i = 0; i < params.max_browser_points; ++i)
        std::swap(keep[i], keep[i + std::uniform_int_distribution<std::size_t>(0, keep.size() - 1 - i)(rng)]);
      keep.resize(params.max_browser_points);
      std::sort(keep.begin(), keep.end());
      out.cloud_subsampled = true;
      out.notes.push_back(fmt::format("3D view: cloud subsampled from {} to {} points (seeded random; the limit is {})", in.cloud.size(),
                                      keep.size(), params.max_browser_points));
    }
    std::vector<float> pos;
    std::vector<std::uint8_t> col;
    for (std::size_t i : keep) {
      for (int k = 0; k < 3; ++k) pos.push_back(float(in.cloud.positions[i][k] - centre[k]));
      const auto c = deviation ? scale.color(deviation->values[i])
                               : in.cloud.has_colors() ? std::array<std::uint8_t, 3>{std::uint8_t(255 * std::clamp(in.cloud.colors[i].x(), 0.f, 1.f)),
                                                                                     std::uint8_t(255 * std::clamp(in.cloud.colors[i].y(), 0.f, 1.f)),
                                                                                     std::uint8_t(255 * std::clamp(in.cloud.colors[i].z(), 0.f, 1.f))}
                                                       : std::array<std::uint8_t, 3>{60, 100, 160};
      col.insert(col.end(), c.begin(), c.end());
    }
    payload["cloud"] = {{"positions", base64(pos)}, {"colors", base64(col)}, {"points", keep.size()}, {"original_points", in.cloud.size()}};
    out.points_shown = keep.size();
  }
  if (deviation) {
    json stops = json::array();
    for (int k = 0; k <= 20; ++k) stops.push_back(hex(scale.color(scale.min + (scale.max - scale.min) * k / 20.0)));
    payload["legend"] = {{"field", "deviation"}, {"min", scale.min}, {"max", scale.max}, {"tolerance", tolerance}, {"stops", stops}};
  }
  if (hist && hist->contains("edges") && hist->contains("counts")) {
    const json& edges = (*hist)["edges"];
    json centres = json::array(), colours = json::array();
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
      const double c = 0.5 * (edges[i].get<double>() + edges[i + 1].get<double>());
      centres.push_back(c);
      colours.push_back(hex(scale.color(c)));
    }
    payload["histogram"] = {{"centres", centres}, {"counts", (*hist)["counts"]}, {"colors", colours}};
  }
  json stage_chart = json::array();
  for (const json& st : stages) {
    // A stage's own tag says more than its type ("crust_30000"); the default tag repeats it.
    const std::string type = st.value("type", ""), tag = st.value("tag", "");
    const bool named = tag != fmt::format("{}{}", type, st.value("index", 0));
    stage_chart.push_back({{"label", fmt::format("{} {}", st.value("index", 0), named ? tag : type)},
                           {"seconds", st.value("seconds", 0.0)},
                           {"peak_rss_mb", st.value("peak_rss_mb", 0.0)},
                           {"rss_rise_mb", st.value("rss_rise_mb", 0.0)}});
  }
  payload["stages"] = stage_chart;
  payload["notes"] = out.notes;
  payload["report"] = report;

  // PNG views from pointsurf's own renderer.
  std::string pictures;
  RenderParams rp;
  rp.size = {params.view_width, params.view_height};
  rp.supersample = 2;
  if (has_mesh) {
    PointCloud verts = in.mesh_vertices;
    if (!mesh_values.empty()) {
      verts.fields.add("deviation", verts.size()).values = mesh_values;
      rp.field = "deviation";
      rp.scale = scale;
    }
    for (View v : {View::Iso, View::Front, View::Side, View::Top}) {
      rp.view = v;
      pictures += png_tag(render_scene(verts, in.mesh_triangles, rp), fmt::format("mesh, {} view{}", view_names().name(v), rp.field.empty() ? "" : ", deviation"));
    }
  }
  if (!in.cloud.empty()) {
    rp.view = View::Iso;
    rp.field = deviation ? "deviation" : "";
    rp.scale = deviation ? std::optional<ColorScale>(scale) : std::nullopt;
    pictures += png_tag(render_scene(in.cloud, {}, rp), fmt::format("cloud, iso view{}", deviation ? ", deviation" : ""));
  }

  // Static tables.
  const std::string status = report.value("status", "?");
  std::string summary = fmt::format(
      "<table class=\"kv\"><tbody><tr><td>pipeline</td><td>{}</td></tr><tr><td>command</td><td>{}</td></tr><tr><td>status</td><td class=\"{}\">{}</td></tr>"
      "<tr><td>total time</td><td>{:.3f} s</td></tr><tr><td>peak memory</td><td>{:.1f} MiB</td></tr><tr><td>pointsurf</td><td>{}</td></tr>"
      "<tr><td>outputs</td><td>{}</td></tr></tbody></table>",
      escape(report.value("pipeline", "")), escape(report.value("command", "")), status == "ok" ? "ok" : "bad", escape(status),
      report.value("total_seconds", 0.0), report.value("peak_rss_mb", 0.0), escape(report.value("version", "")),
      escape(value_text(report.value("outputs", json::array()))));
  if (report.contains("error")) summary += fmt::format("<p class=\"bad\">error: {}</p>", escape(report["error"].value("message", "")));

  std::string deviation_table;
  if (dev_block) {
    std::vector<std::pair<std::string, std::string>> rows;
    for (const char* k : {"count", "max_positive", "max_negative", "mean_positive", "mean_negative", "mean", "mean_absolute", "rms", "std",
                          "tolerance", "within_tolerance"})
      if (dev_block->contains(k)) rows.emplace_back(k, value_text((*dev_block)[k]));
    deviation_table = table(rows, "deviation", "value");
  }

  std::string stage_rows;
  std::string details;
  for (const json& st : stages) {
    const std::string name = fmt::format("{} {} ({})", st.value("index", 0), st.value("type", ""), st.value("tag", ""));
    stage_rows += fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3f}</td><td>{:.1f}</td><td>{:.1f}</td></tr>", st.value("index", 0),
                              escape(st.value("type", "")), escape(value_text(st.value("inputs", json::array()))), st.value("seconds", 0.0),
                              st.value("peak_rss_mb", 0.0), st.value("rss_rise_mb", 0.0));
    std::vector<std::pair<std::string, std::string>> p, m;
    flatten(st.value("parameters", json::object()), "", p);
    flatten(st.value("counts", json::object()), "", m);
    flatten(st.value("metrics", json::object()), "", m);
    std::string warnings;
    for (const json& w : st.value("warnings", json::array())) warnings += "<li>" + escape(w.get<std::string>()) + "</li>";
    details += fmt::format("<details class=\"stage\"{}><summary>{}</summary><div class=\"two\"><div><h4>Parameters</h4>{}</div><div><h4>Counts and "
                           "metrics</h4>{}</div></div>{}</details>",
                           st.value("type", "") == "evaluate" ? " open" : "", escape(name), table(p, "parameter", "value"), table(m, "key", "value"),
                           warnings.empty() ? "" : "<h4>Warnings</h4><ul class=\"warn\">" + warnings + "</ul>");
  }
  std::string warnings;
  for (const json& w : report.value("warnings", json::array())) warnings += "<li>" + escape(w.get<std::string>()) + "</li>";
  std::string notes;
  for (const std::string& n : out.notes) notes += "<li>" + escape(n) + "</li>";

  std::string data = payload.dump();
  // Inside <script>, "</" would end the element: JSON allows "<\/".
  for (std::size_t at = 0; (at = data.find("</", at)) != std::string::npos; at += 3) data.replace(at, 2, "<\\/");

  std::map<std::string, std::string> slots = {
      {"TITLE", escape(in.origin)},
      {"SUMMARY", summary},
      {"NOTES", notes},
      {"PICTURES", pictures.empty() ? "<p>No geometry was written by this run.</p>" : pictures},
      {"DEVIATION_TABLE", deviation_table.empty() ? "<p>This run has no evaluate stage.</p>" : deviation_table},
      {"STAGE_ROWS", stage_rows},
      {"STAGE_DETAILS", details},
      {"WARNINGS", warnings.empty() ? "<p>None.</p>" : "<ul class=\"warn\">" + warnings + "</ul>"},
      {"MESH_TRIANGLES", fmt::format("{}", out.triangles_shown)},
      {"CLOUD_POINTS", fmt::format("{}", out.points_shown)},
      {"THREE_JS", in.three_js},
      {"ORBIT_JS", in.orbit_controls_js},
      {"CHART_JS", in.chart_js},
      {"PAYLOAD", data},
  };
  out.html = detail::fill_page(slots);
  return out;
}

}  // namespace pointsurf
