// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf convert IN OUT: any supported format to any other (the output format follows OUT's
// extension). Faces travel when both formats hold them.
#include <memory>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"

namespace pointsurf::cli {
namespace {

struct ConvertState {
  CommonOptions common;
  OutputOptions output;
  std::string input, output_path;
};

void run_convert(const ConvertState& s) {
  Report report("convert");
  report.parameters() = {{"input", s.input}, {"output", s.output_path}, {"ascii", s.output.ascii},
                         {"float", s.output.single_precision}, {"big_endian", s.output.big_endian},
                         {"compressed", s.output.compressed}};
  const WriteOptions write_options = s.output.to_write_options();
  format_from_extension(s.output_path);  // a bad output extension is a usage error before any reading
  const std::string format = s.common.input_format.empty() ? detect_format(s.input) : ascii_lower(s.common.input_format);
  const bool mesh_format = format == "ply" || format == "off" || format == "obj" || format == "stl";
  ReadOptions options;
  options.strict = s.common.strict;
  options.columns = s.common.columns;
  options.format = format;  // detected once here, not again by the reader

  TriangleMesh mesh;
  const std::size_t read_stage = report.begin_stage("read");
  std::size_t dropped = 0;
  std::vector<std::string> warnings;
  if (mesh_format) {
    MeshReadResult r = read_mesh(s.input, options);
    dropped = r.dropped_nonfinite;
    warnings = std::move(r.warnings);
    if (r.dropped_faces > 0) warnings.push_back(fmt::format("{} degenerate faces dropped", r.dropped_faces));
    if (r.polygons_triangulated > 0) warnings.push_back(fmt::format("{} polygons split into triangles", r.polygons_triangulated));
    mesh = std::move(r.mesh);
  } else {
    CloudReadResult r = read_point_cloud(s.input, options);
    dropped = r.dropped_nonfinite;
    warnings = std::move(r.warnings);
    mesh = TriangleMesh::from_cloud(std::move(r.cloud), {});
  }
  report.end_stage(read_stage);
  report.stage(read_stage)["counts"] = {{"points", mesh.vertex_count()}, {"faces", mesh.triangle_count()}, {"dropped_nonfinite", dropped}};
  report.add_input({{"path", s.input}, {"format", format}, {"points", mesh.vertex_count()}, {"faces", mesh.triangle_count()},
                    {"dropped_nonfinite", dropped}});
  for (const std::string& w : warnings) report.warn(with_file(s.input, w), s.common.quiet);
  if (dropped > 0)
    report.warn(fmt::format("{}: {} points with NaN/Inf coordinates dropped (--strict makes this an error)", s.input, dropped),
                s.common.quiet);
  if (mesh.vertices.empty()) throw InputError(fmt::format("{}: no points", s.input));

  warn_lost_attributes(s.output_path, !mesh.vertex_normals.empty(), !mesh.vertex_colors.empty(), mesh.vertex_fields, mesh.triangle_count(),
                       write_options, s.common, report);
  const std::size_t write_stage = report.begin_stage("write");
  write_mesh(s.output_path, mesh, write_options);
  report.end_stage(write_stage);
  const std::string out_format = write_options.format.empty() ? format_from_extension(s.output_path) : write_options.format;
  const bool holds_faces = out_format == "ply" || out_format == "off" || out_format == "obj" || out_format == "stl";
  const std::size_t faces_written = holds_faces ? mesh.triangle_count() : 0;
  report.stage(write_stage)["counts"] = {{"points", mesh.vertex_count()}, {"faces", faces_written}};
  report.add_output({{"path", s.output_path}, {"format", out_format}, {"points", mesh.vertex_count()}, {"faces", faces_written}});
  report.finish();
  if (!s.common.report_path.empty()) report.write(s.common.report_path);
  if (!s.common.quiet)
    fmt::print(stderr, "{} -> {}: {} points, {} faces\n", s.input, s.output_path, mesh.vertex_count(), faces_written);
}

}  // namespace

Command register_convert(CLI::App& app) {
  auto state = std::make_shared<ConvertState>();
  CLI::App* cmd = app.add_subcommand("convert", "Convert between formats; the output format follows OUT's extension");
  cmd->add_option("input", state->input, "Input file")->required();
  cmd->add_option("output", state->output_path, "Output file (.ply .xyz .txt .pts .csv .pcd .las .off .obj .stl)")->required();
  add_common_options(*cmd, state->common);
  add_output_options(*cmd, state->output);
  return {cmd, [state] { run_convert(*state); }, &state->common};
}

const CommandRegistration convert_registration{20, register_convert};

}  // namespace pointsurf::cli
