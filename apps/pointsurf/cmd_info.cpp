// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf info IN [--json]: format, counts, bounding box, mean spacing, fields.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <utility>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {
namespace {

struct InfoState {
  CommonOptions common;
  std::string input;
  bool json = false;
};

std::string scalar_type_name(ScalarType t) { return std::string(scalar_type_ply_name(t)); }

void run_info(const InfoState& s) {
  Report report("info");
  report.parameters() = {{"input", s.input}};
  const std::string format = s.common.input_format.empty() ? detect_format(s.input) : ascii_lower(s.common.input_format);
  const bool mesh_format = format == "ply" || format == "off" || format == "obj" || format == "stl";

  PointCloud cloud;
  std::size_t faces = 0;
  nlohmann::json info;
  {
    const std::size_t stage = report.begin_stage("read");
    ReadOptions options;
    options.strict = s.common.strict;
    options.columns = s.common.columns;
    options.format = format;  // detected once above, not again by the reader
    if (mesh_format) {
      MeshReadResult r = read_mesh(s.input, options);
      faces = r.mesh.triangle_count();
      info["encoding"] = r.encoding;
      info["dropped_nonfinite"] = r.dropped_nonfinite;
      info["dropped_faces"] = r.dropped_faces;
      info["polygons_triangulated"] = r.polygons_triangulated;
      for (const std::string& w : r.warnings) report.warn(with_file(s.input, w), true);
      // The mesh is not used again: its vertex data moves into the cloud instead of being copied.
      cloud.positions = std::move(r.mesh.vertices);
      cloud.normals = std::move(r.mesh.vertex_normals);
      cloud.colors = std::move(r.mesh.vertex_colors);
      cloud.fields = std::move(r.mesh.vertex_fields);
    } else {
      CloudReadResult r = read_point_cloud(s.input, options);
      info["encoding"] = r.encoding;
      info["dropped_nonfinite"] = r.dropped_nonfinite;
      for (const std::string& w : r.warnings) report.warn(with_file(s.input, w), true);
      cloud = std::move(r.cloud);
    }
    report.end_stage(stage);
    report.stage(stage)["counts"]["points"] = cloud.size();
  }
  info["path"] = s.input;
  info["format"] = format;
  info["points"] = cloud.size();
  info["faces"] = faces;
  info["normals"] = cloud.has_normals();
  info["colors"] = cloud.has_colors();
  const BoundingBox box = bounding_box(cloud.positions);
  if (!box.empty()) {
    info["bbox_min"] = {box.min.x(), box.min.y(), box.min.z()};
    info["bbox_max"] = {box.max.x(), box.max.y(), box.max.z()};
    info["bbox_diagonal"] = box.diagonal();
  }
  if (cloud.size() >= 2) {
    const std::size_t stage = report.begin_stage("mean_spacing");
    const double spacing = mean_spacing(cloud.positions);
    report.end_stage(stage);
    report.stage(stage)["metrics"]["mean_spacing"] = spacing;
    info["mean_spacing"] = spacing;
  }
  nlohmann::json fields = nlohmann::json::array();
  for (const ScalarField& f : cloud.fields) {
    const auto [lo, hi] = f.values.empty() ? std::pair<double, double>{0.0, 0.0}
                                            : std::pair<double, double>{*std::min_element(f.values.begin(), f.values.end()),
                                                                        *std::max_element(f.values.begin(), f.values.end())};
    fields.push_back({{"name", f.name}, {"type", scalar_type_name(f.type)}, {"min", lo}, {"max", hi}});
  }
  info["fields"] = fields;
  report.add_input(info);
  report.finish();
  if (!s.common.report_path.empty()) report.write(s.common.report_path);

  if (s.json) {
    fmt::print("{}\n", info.dump(2));
    return;
  }
  fmt::print("file         {}\n", s.input);
  fmt::print("format       {} ({})\n", format, info["encoding"].get<std::string>());
  fmt::print("points       {}\n", cloud.size());
  if (mesh_format) fmt::print("faces        {}\n", faces);
  if (info["dropped_nonfinite"].get<std::size_t>() > 0)
    fmt::print("dropped      {} points with NaN/Inf coordinates\n", info["dropped_nonfinite"].get<std::size_t>());
  fmt::print("normals      {}\n", cloud.has_normals() ? "yes" : "no");
  fmt::print("colours      {}\n", cloud.has_colors() ? "yes" : "no");
  if (!box.empty()) {
    fmt::print("bbox min     {:.6f} {:.6f} {:.6f}\n", box.min.x(), box.min.y(), box.min.z());
    fmt::print("bbox max     {:.6f} {:.6f} {:.6f}\n", box.max.x(), box.max.y(), box.max.z());
    fmt::print("extent       {:.6g} {:.6g} {:.6g} (diagonal {:.6g})\n", box.extent().x(), box.extent().y(), box.extent().z(),
               box.diagonal());
  }
  if (info.contains("mean_spacing")) fmt::print("mean spacing {:.6g}\n", info["mean_spacing"].get<double>());
  for (const auto& f : fields)
    fmt::print("field        {} ({}) range [{:g}, {:g}]\n", f["name"].get<std::string>(), f["type"].get<std::string>(),
               f["min"].get<double>(), f["max"].get<double>());
  for (const auto& w : report.json()["warnings"]) fmt::print("warning      {}\n", w.get<std::string>());
}

}  // namespace

Command register_info(CLI::App& app) {
  auto state = std::make_shared<InfoState>();
  CLI::App* cmd = app.add_subcommand("info", "Describe a cloud or mesh: format, counts, bounding box, mean spacing, fields");
  cmd->add_option("input", state->input, "Input file")->required();
  cmd->add_flag("--json", state->json, "Print the description as JSON on stdout");
  add_common_options(*cmd, state->common);
  return {cmd, [state] { run_info(*state); }, &state->common};
}

const CommandRegistration info_registration{10, register_info};

}  // namespace pointsurf::cli
