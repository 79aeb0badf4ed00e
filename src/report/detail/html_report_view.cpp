// SPDX-License-Identifier: GPL-3.0-or-later
// The report's view model, one phase per part of the page: the summary and stages (text from
// the run report), the deviation (the last evaluate stage), the geometry of the 3D view and the
// PNG views. The colour scale is shared: the mesh, the cloud, the legend, the histogram and the
// pictures all use the one from the cloud's field "deviation".
#include "report/detail/html_report_view.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <unordered_map>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/deviation_stats.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/render/render_scene.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::detail {
namespace {

using nlohmann::json;

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

void flatten(const json& v, const std::string& prefix, TextRows& out) {
  if (v.is_object()) {
    for (auto it = v.begin(); it != v.end(); ++it) flatten(it.value(), prefix.empty() ? it.key() : prefix + "/" + it.key(), out);
    return;
  }
  out.emplace_back(prefix, value_text(v));
}

std::vector<std::string> texts(const json& list) {
  std::vector<std::string> out;
  for (const json& w : list) out.push_back(w.get<std::string>());
  return out;
}

RunSummaryView summary_view(const json& report) {
  RunSummaryView s;
  s.pipeline = report.value("pipeline", "");
  s.command = report.value("command", "");
  s.status = report.value("status", "?");
  s.total_seconds = report.value("total_seconds", 0.0);
  s.peak_rss_mb = report.value("peak_rss_mb", 0.0);
  s.version = report.value("version", "");
  s.outputs = value_text(report.value("outputs", json::array()));
  if (report.contains("error")) s.error = report["error"].value("message", "");
  return s;
}

StageView stage_view(const json& st) {
  StageView s;
  s.index = st.value("index", 0);
  s.type = st.value("type", "");
  s.tag = st.value("tag", "");
  // A stage's own tag says more than its type ("crust_30000"); the default tag repeats it.
  const bool named = s.tag != fmt::format("{}{}", s.type, s.index);
  s.chart_label = fmt::format("{} {}", s.index, named ? s.tag : s.type);
  s.inputs = value_text(st.value("inputs", json::array()));
  s.seconds = st.value("seconds", 0.0);
  s.peak_rss_mb = st.value("peak_rss_mb", 0.0);
  s.rss_rise_mb = st.value("rss_rise_mb", 0.0);
  flatten(st.value("parameters", json::object()), "", s.parameters);
  flatten(st.value("counts", json::object()), "", s.counts_and_metrics);
  flatten(st.value("metrics", json::object()), "", s.counts_and_metrics);
  s.warnings = texts(st.value("warnings", json::array()));
  s.expanded = s.type == "evaluate";
  return s;
}

// The tolerance of the last evaluate stage that gives a numeric one; 0 when none does.
double evaluated_tolerance(const json& stages) {
  double tolerance = 0.0;
  for (const json& st : stages)
    if (st.value("type", "") == "evaluate")
      if (const json* t = find_path(st, {"metrics", "deviation", "tolerance"}); t && t->is_number()) tolerance = t->get<double>();
  return tolerance;
}

// The deviation block of the last evaluate stage; the histogram's colours follow `scale`.
DeviationView deviation_view(const json& stages, const ColorScale& scale) {
  DeviationView d;
  d.tolerance = evaluated_tolerance(stages);
  const json* block = nullptr;
  const json* hist = nullptr;
  for (const json& st : stages)
    if (st.value("type", "") == "evaluate") {
      block = find_path(st, {"metrics", "deviation"});
      hist = find_path(st, {"metrics", "deviation", "histogram"});
    }
  if (block) {
    d.evaluated = true;
    // The headline statistics of the deviation's declaration (DeviationStats::results()).
    for (const ResultSpec& spec : DeviationStats::results().specs())
      if (spec.headline && block->contains(spec.key)) d.statistics.emplace_back(spec.key, value_text((*block)[spec.key]));
  }
  if (hist && hist->contains("edges") && hist->contains("counts")) {
    const json& edges = (*hist)["edges"];
    DeviationView::Histogram h;
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
      const double c = 0.5 * (edges[i].get<double>() + edges[i + 1].get<double>());
      h.centres.push_back(c);
      h.colors.push_back(scale.color(c));
    }
    h.counts = (*hist)["counts"];
    d.histogram = std::move(h);
  }
  return d;
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
    std::vector<int> count, measured;
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      const Vector3d q = (vertices[i] - box.min) / cell;
      const std::uint64_t key = (std::uint64_t(q.x()) & 0x1FFFFF) | (std::uint64_t(q.y()) & 0x1FFFFF) << 21 | (std::uint64_t(q.z()) & 0x1FFFFF) << 42;
      auto [it, fresh] = index.emplace(key, std::int32_t(sum.size()));
      if (fresh) {
        sum.push_back(Vector3d::Zero());
        vsum.push_back(0.0);
        count.push_back(0);
        measured.push_back(0);
      }
      map[i] = it->second;
      sum[std::size_t(it->second)] += vertices[i];
      if (!values.empty() && std::isfinite(values[i])) {  // NaN: not measured
        vsum[std::size_t(it->second)] += values[i];
        ++measured[std::size_t(it->second)];
      }
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
      vsum[c] = measured[c] > 0 ? vsum[c] / double(measured[c]) : std::numeric_limits<double>::quiet_NaN();
    }
    vertices = std::move(sum);
    if (!values.empty()) values = std::move(vsum);
    triangles = std::move(kept);
    return;
  }
}

BrowserMesh browser_mesh(const HtmlReportInputs& in, const std::vector<double>& mesh_values, const ColorScale& scale, const Vector3d& centre,
                         const HtmlReportParams& params, HtmlReportView& view) {
  std::vector<Vector3d> v = in.mesh.vertices.positions;
  std::vector<double> values = mesh_values;
  std::vector<Triangle> t = in.mesh.triangles;
  if (t.size() > params.max_browser_triangles) {
    decimate(v, values, t, params.max_browser_triangles);
    view.mesh_decimated = true;
    view.notes.push_back(fmt::format("3D view: mesh decimated from {} to {} triangles (vertex clustering; the limit is {})", in.mesh.triangles.size(),
                                     t.size(), params.max_browser_triangles));
  }
  BrowserMesh m;
  for (const Vector3d& p : v)
    for (int k = 0; k < 3; ++k) m.positions.push_back(float(p[k] - centre[k]));
  for (const Triangle& tri : t)
    for (int k = 0; k < 3; ++k) m.indices.push_back(std::uint32_t(tri[k]));
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Rgb c = values.empty() ? Rgb{190, 196, 206} : scale.color(values[i]);
    m.colors.insert(m.colors.end(), c.begin(), c.end());
  }
  m.vertices = v.size();
  m.triangles = t.size();
  m.original_triangles = in.mesh.triangles.size();
  return m;
}

BrowserCloud browser_cloud(const PointCloud& cloud, const ScalarField* deviation, const ColorScale& scale, const Vector3d& centre,
                           const HtmlReportParams& params, HtmlReportView& view) {
  std::vector<std::size_t> keep(cloud.size());
  std::iota(keep.begin(), keep.end(), std::size_t(0));
  if (keep.size() > params.max_browser_points) {
    std::mt19937_64 rng(params.seed);
    for (std::size_t i = 0; i < params.max_browser_points; ++i)
      std::swap(keep[i], keep[i + std::uniform_int_distribution<std::size_t>(0, keep.size() - 1 - i)(rng)]);
    keep.resize(params.max_browser_points);
    std::sort(keep.begin(), keep.end());
    view.cloud_subsampled = true;
    view.notes.push_back(fmt::format("3D view: cloud subsampled from {} to {} points (seeded random; the limit is {})", cloud.size(), keep.size(),
                                     params.max_browser_points));
  }
  BrowserCloud c;
  for (std::size_t i : keep) {
    for (int k = 0; k < 3; ++k) c.positions.push_back(float(cloud.positions[i][k] - centre[k]));
    const Rgb rgb = deviation            ? scale.color(deviation->values[i])
                    : cloud.has_colors() ? Rgb{std::uint8_t(255 * std::clamp(cloud.colors[i].x(), 0.f, 1.f)),
                                               std::uint8_t(255 * std::clamp(cloud.colors[i].y(), 0.f, 1.f)),
                                               std::uint8_t(255 * std::clamp(cloud.colors[i].z(), 0.f, 1.f))}
                                         : Rgb{60, 100, 160};
    c.colors.insert(c.colors.end(), rgb.begin(), rgb.end());
  }
  c.points = keep.size();
  c.original_points = cloud.size();
  return c;
}

// PNG views from pointsurf's own renderer, of the full mesh and cloud.
std::vector<PictureView> pictures(const HtmlReportInputs& in, const std::vector<double>& mesh_values, const ScalarField* deviation,
                                  const ColorScale& scale, const HtmlReportParams& params) {
  std::vector<PictureView> out;
  RenderParams rp;
  rp.size = {params.view_width, params.view_height};
  rp.supersample = 2;
  if (!in.mesh.triangles.empty()) {
    PointCloud verts = in.mesh.vertices;
    if (!mesh_values.empty()) {
      verts.fields.add("deviation", verts.size()).values = mesh_values;
      rp.field = "deviation";
      rp.scale = scale;
    }
    for (View v : {View::Iso, View::Front, View::Side, View::Top}) {
      rp.view = v;
      out.push_back({fmt::format("mesh, {} view{}", view_names().name(v), rp.field.empty() ? "" : ", deviation"),
                     encode_png(render_scene(verts, in.mesh.triangles, rp).image)});
    }
  }
  if (!in.cloud.empty()) {
    rp.view = View::Iso;
    rp.field = deviation ? "deviation" : "";
    rp.scale = deviation ? std::optional<ColorScale>(scale) : std::nullopt;
    out.push_back({fmt::format("cloud, iso view{}", deviation ? ", deviation" : ""), encode_png(render_scene(in.cloud, {}, rp).image)});
  }
  return out;
}

}  // namespace

nlohmann::json parse_run_report(const std::string& text, const std::string& origin) {
  try {
    return json::parse(text);
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}: not a run report (JSON): {}", origin, e.what()));
  }
}

const nlohmann::json* find_path(const nlohmann::json& j, std::initializer_list<const char*> keys) {
  const json* at = &j;
  for (const char* k : keys) {
    if (!at->is_object() || !at->contains(k)) return nullptr;
    at = &(*at)[k];
  }
  return at;
}

HtmlReportView html_report_view(const HtmlReportInputs& in, const HtmlReportParams& params) {
  HtmlReportView view;
  view.run_report = parse_run_report(in.run_json, in.origin);
  view.title = in.origin;
  const json stages = view.run_report.value("stages", json::array());

  // The deviation scale: evaluate's tolerance as the band. Without the field the default scale
  // still colours the histogram.
  const ScalarField* deviation = in.cloud.fields.find("deviation");
  ColorScale scale;
  if (deviation) scale = default_color_scale(deviation->values, "deviation", false, evaluated_tolerance(stages));
  view.deviation = deviation_view(stages, scale);
  if (deviation) {
    LegendView legend{scale.low(), scale.high(), view.deviation.tolerance, {}, ColorScale::kUnderRange, ColorScale::kOverRange};
    for (int k = 0; k <= 20; ++k) legend.stops.push_back(scale.color(scale.low() + (scale.high() - scale.low()) * k / 20.0));
    view.legend = std::move(legend);
  }

  // Geometry for the browser, about the centre of everything shown.
  BoundingBox box;
  for (const Vector3d& p : in.mesh.vertices.positions) box.extend(p);
  for (const Vector3d& p : in.cloud.positions) box.extend(p);
  const Vector3d centre = box.center();
  view.centre = {centre.x(), centre.y(), centre.z()};
  view.radius = 0.5 * box.diagonal();
  const bool has_mesh = !in.mesh.triangles.empty();
  std::vector<double> mesh_values;
  if (has_mesh && deviation) {
    mesh_values = vertex_deviation_from_points(in.mesh, in.cloud.positions, deviation->values);
    view.notes.push_back(
        "mesh coloured at each vertex by the deviation of the measured points closest to its triangles (their signed RMS; grey: no "
        "point measured there); the measured points by their own deviation");
  }
  if (has_mesh) view.mesh = browser_mesh(in, mesh_values, scale, centre, params, view);
  if (!in.cloud.empty()) view.cloud = browser_cloud(in.cloud, deviation, scale, centre, params, view);
  view.pictures = pictures(in, mesh_values, deviation, scale, params);

  view.summary = summary_view(view.run_report);
  for (const json& st : stages) view.stages.push_back(stage_view(st));
  view.warnings = texts(view.run_report.value("warnings", json::array()));
  view.three_js = in.three_js;
  view.orbit_controls_js = in.orbit_controls_js;
  view.chart_js = in.chart_js;
  return view;
}

}  // namespace pointsurf::detail
