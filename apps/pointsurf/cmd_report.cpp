// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf report RUN.json OUT.html: the offline HTML report of a run (pointsurf/report/html_report.h),
// and the same for `pointsurf run --html FILE`. Here the files are read: the run report, the
// mesh and cloud it names, and the JavaScript libraries from Debian's libjs-three and
// libjs-chart.js (or POINTSURF_JS_DIR), which the page inlines.
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/report/html_report.h"

namespace pointsurf::cli {
namespace {

std::string read_text(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot read {}", path.string(), what));
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string javascript(const std::string& relative, const std::string& package) {
  const char* dir = std::getenv("POINTSURF_JS_DIR");
  const std::filesystem::path path = std::filesystem::path(dir ? dir : "/usr/share/javascript") / relative;
  if (!std::filesystem::exists(path))
    throw InputError(fmt::format("{}: missing: the report inlines it (install Debian's {}, or set POINTSURF_JS_DIR)", path.string(), package));
  return read_text(path, "the JavaScript library");
}

// A file the run wrote: as named (the run's working directory), else beside the report.
std::filesystem::path locate(const std::string& file, const std::filesystem::path& report_dir) {
  if (std::filesystem::exists(file) || std::filesystem::path(file).is_absolute()) return file;
  const std::filesystem::path beside = report_dir / std::filesystem::path(file).filename();
  return std::filesystem::exists(beside) ? beside : std::filesystem::path(file);
}

std::string report_help() {
  return "pointsurf report RUN.json OUT.html [options]\n"
         "Write the HTML report of a run (from its --report JSON): one file that opens offline, with a 3D view of the mesh\n"
         "(coloured by deviation when the run evaluated it) and the cloud, PNG views, the deviation histogram, time and memory\n"
         "per stage, and every metric and parameter. The mesh and cloud are read from the files the run wrote.\n\n"
         "Options:\n"
         "  --max-triangles N    Decimate the 3D view's mesh above N triangles (default " +
         std::to_string(HtmlReportParams{}.max_browser_triangles) +
         ")\n"
         "  --max-points N       Subsample the 3D view's cloud above N points (default " +
         std::to_string(HtmlReportParams{}.max_browser_points) + ")\n" + common_options_help() +
         "\nExample:\n"
         "  pointsurf run examples/kitten_mesh.json --report out/kitten_run.json\n"
         "  pointsurf report out/kitten_run.json out/kitten_report.html\n";
}

int run_report(const std::vector<std::string>& args) {
  CommonOptions common;
  HtmlReportParams params;
  auto count = [](const std::string& name, const std::string& v) {
    try {
      const long long n = std::stoll(v);
      if (n >= 1) return std::size_t(n);
    } catch (const std::exception&) {
    }
    throw UsageError(fmt::format("{}: \"{}\" is not a positive integer", name, v));
  };
  std::vector<OptionDef> options = {
      {"--max-triangles", false, "N", [&](const std::string& v) { params.max_browser_triangles = count("--max-triangles", v); }},
      {"--max-points", false, "N", [&](const std::string& v) { params.max_browser_points = count("--max-points", v); }}};
  add_common_options(options, common);
  const std::vector<std::string> positionals = scan_arguments(args, options);
  if (common.help) {
    fmt::print("{}", report_help());
    return 0;
  }
  if (positionals.size() != 2)
    throw UsageError(fmt::format("expected RUN.json OUT.html, got {} file names (see pointsurf report --help)", positionals.size()));
  check_common_options(common);
  const std::string& run_file = positionals[0];
  check_input_path(run_file);
  write_html_report(read_text(run_file, "the run report"), run_file, positionals[1], params, common);
  return 0;
}

}  // namespace

void write_html_report(const std::string& run_json, const std::string& origin, const std::string& out_path, const HtmlReportParams& params,
                       const CommonOptions& common) {
  check_output_path(out_path, common.no_clobber, "html");
  HtmlReportInputs in;
  in.run_json = run_json;
  in.origin = origin;
  const ReportSources sources = report_sources(run_json, origin);
  const std::filesystem::path dir = std::filesystem::path(origin).parent_path();
  if (!sources.mesh_file.empty()) {
    MeshReadResult m = read_mesh(locate(sources.mesh_file, dir));
    in.mesh.vertices.positions = std::move(m.mesh.vertices.positions);  // its shape: the page colours it by deviation
    in.mesh.triangles = std::move(m.mesh.triangles);
  }
  if (!sources.cloud_file.empty()) in.cloud = read_point_cloud(locate(sources.cloud_file, dir)).cloud;
  in.three_js = javascript("three/three.min.js", "libjs-three");
  in.orbit_controls_js = javascript("three/examples/js/controls/OrbitControls.js", "libjs-three");
  in.chart_js = javascript("chart.js/chart.min.js", "libjs-chart.js");
  const HtmlReport report = build_html_report(in, params);
  write_text_atomically(out_path, report.html);
  if (!common.quiet) {
    fmt::print(stderr, "report: {} ({:.1f} MB; 3D view: {} triangles, {} points)\n", out_path, double(report.html.size()) / 1e6,
               report.triangles_shown, report.points_shown);
    for (const std::string& n : report.notes) fmt::print(stderr, "note: {}\n", n);
  }
}

Command report_command() {
  return {"report", "Write the offline HTML report of a run: pointsurf report RUN.json OUT.html", run_report, report_help, {}};
}

}  // namespace pointsurf::cli
