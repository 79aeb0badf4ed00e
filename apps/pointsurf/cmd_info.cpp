// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf info IN [--json]: format, counts, bounding box, mean spacing, fields.
#include <algorithm>
#include <cstdio>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/formats.h"
#include "pointsurf/io/io.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {
namespace {

std::string info_help() {
  return "pointsurf info IN [--json] [options]\nDescribe a cloud or mesh: format, counts, bounding box, mean spacing, fields.\n\n"
         "Options:\n"
         "  --json                         Print the description as JSON on stdout\n"
         "  --columns SPEC                 Column meaning of XYZ/TXT/CSV input (see pointsurf normals --help)\n"
         "  --input-format FORMAT          Read as this format instead of detecting it: " + known_format_names(", ") + "\n"
         "  --strict                       Points with NaN/Inf coordinates are an error\n\n" +
         common_options_help() + "\nExample:\n  pointsurf info data/b9_training.ply --json\n";
}

int run_info(const std::vector<std::string>& args) {
  CommonOptions common;
  bool json = false;
  ReadOptions options;
  auto boolean = [](bool& target) {
    return [&target](const std::string& v) {
      if (v != "true" && v != "false") throw UsageError(fmt::format("\"{}\" is not true or false", v));
      target = v == "true";
    };
  };
  std::vector<OptionDef> defs = {{"--json", true, "", boolean(json)},
                                 {"--strict", true, "", boolean(options.strict)},
                                 {"--columns", false, "SPEC", [&](const std::string& v) { options.columns = v; }},
                                 {"--input-format", false, "FORMAT", [&](const std::string& v) { options.format = v; }}};
  add_common_options(defs, common);
  const std::vector<std::string> positionals = scan_arguments(args, defs);
  if (common.help) {
    fmt::print("{}", info_help());
    return 0;
  }
  if (positionals.size() != 1) throw UsageError(fmt::format("expected one input file, got {} (see pointsurf info --help)", positionals.size()));
  check_common_options(common);
  const std::string& input = positionals.front();
  check_input_path(input);
  const auto start = std::chrono::steady_clock::now();
  const std::string format = options.format.empty() ? detect_format(input) : options.format;
  const bool mesh_format = file_format(format).holds_faces;
  options.format = format;

  PointCloud cloud;
  FieldSet face_fields;
  std::size_t faces = 0;
  nlohmann::json info;
  std::vector<std::string> warnings;
  if (mesh_format) {
    MeshReadResult r = read_mesh(input, options);
    faces = r.mesh.triangle_count();
    info["encoding"] = r.encoding;
    info["dropped_nonfinite"] = r.dropped_nonfinite;
    info["dropped_faces"] = r.dropped_faces;
    info["polygons_triangulated"] = r.polygons_triangulated;
    warnings = std::move(r.warnings);
    cloud = std::move(r.mesh.vertices);
    face_fields = std::move(r.mesh.face_fields);
  } else {
    CloudReadResult r = read_point_cloud(input, options);
    info["encoding"] = r.encoding;
    info["dropped_nonfinite"] = r.dropped_nonfinite;
    warnings = std::move(r.warnings);
    cloud = std::move(r.cloud);
    // E57: each scan with its pose (rotation as a unit quaternion w x y z, then translation).
    for (const ScanPose& s : r.scans)
      info["scans"].push_back({{"name", s.name},
                               {"points", s.points},
                               {"rotation_wxyz", {s.rotation.w(), s.rotation.x(), s.rotation.y(), s.rotation.z()}},
                               {"translation", {s.translation.x(), s.translation.y(), s.translation.z()}}});
  }
  // A file of words read as text gives no point: that is bad input, not an empty answer.
  if (cloud.empty()) throw InputError(fmt::format("{}: no points (is it a point cloud?)", input));
  info["path"] = input;
  info["format"] = format;
  info["points"] = cloud.size();
  info["faces"] = faces;
  info["normals"] = cloud.has_normals();
  info["colors"] = cloud.has_colors();
  const BoundingBox box = bounding_box(cloud.positions);
  info["bbox_min"] = {box.min.x(), box.min.y(), box.min.z()};
  info["bbox_max"] = {box.max.x(), box.max.y(), box.max.z()};
  info["bbox_diagonal"] = box.diagonal();
  if (cloud.size() >= 2) info["mean_spacing"] = mean_spacing(cloud.positions);
  // Name, type and range of each field (vertex or face).
  auto describe = [](const FieldSet& set) {
    nlohmann::json out = nlohmann::json::array();
    for (const ScalarField& f : set) {
      const auto [lo, hi] = f.values.empty() ? std::pair<double, double>{0.0, 0.0}
                                              : std::pair<double, double>{*std::min_element(f.values.begin(), f.values.end()),
                                                                          *std::max_element(f.values.begin(), f.values.end())};
      out.push_back({{"name", f.name}, {"type", std::string(scalar_type_ply_name(f.type))}, {"min", lo}, {"max", hi}});
    }
    return out;
  };
  const nlohmann::json fields = describe(cloud.fields);
  info["fields"] = fields;
  if (mesh_format) info["face_fields"] = describe(face_fields);
  if (!cloud.crs.empty()) {
    nlohmann::json crs = {{"name", cloud.crs.describe()}};
    if (cloud.crs.epsg() > 0) crs["epsg"] = cloud.crs.epsg();
    if (!cloud.crs.wkt.empty()) crs["wkt"] = cloud.crs.wkt;
    crs["geotiff_keys"] = !cloud.crs.geokeys.empty();
    info["crs"] = crs;
  }

  if (!common.report_path.empty()) {
    // The one report schema: a run with one stage "info" whose metrics are the description.
    RunReport report;
    report.command = "info";
    report.origin = input;
    report.ok = true;
    StageRecord r;
    r.index = 1;
    r.type = "info";
    r.tag = "info";
    r.parameters = {{"filename", input}, {"format", format}};
    r.count("points", static_cast<std::int64_t>(cloud.size()));
    r.count("faces", static_cast<std::int64_t>(faces));
    r.metric("description", info.dump());
    r.warnings = warnings;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.peak_rss_mb = peak_rss_mb();
    report.stages.push_back(r);
    report.warnings = warnings;
    report.total_seconds = r.seconds;
    report.peak_rss_mb = r.peak_rss_mb;
    write_text_atomically(common.report_path, report_json(report));
  }
  if (json) {
    fmt::print("{}\n", info.dump(2));
    return 0;
  }
  fmt::print("file         {}\n", input);
  fmt::print("format       {} ({})\n", format, info["encoding"].get<std::string>());
  fmt::print("points       {}\n", cloud.size());
  if (mesh_format) fmt::print("faces        {}\n", faces);
  if (info["dropped_nonfinite"].get<std::size_t>() > 0)
    fmt::print("dropped      {} points with NaN/Inf coordinates\n", info["dropped_nonfinite"].get<std::size_t>());
  fmt::print("normals      {}\n", cloud.has_normals() ? "yes" : "no");
  fmt::print("colours      {}\n", cloud.has_colors() ? "yes" : "no");
  if (!cloud.crs.empty()) fmt::print("crs          {}\n", cloud.crs.describe());
  fmt::print("bbox min     {:.6f} {:.6f} {:.6f}\n", box.min.x(), box.min.y(), box.min.z());
  fmt::print("bbox max     {:.6f} {:.6f} {:.6f}\n", box.max.x(), box.max.y(), box.max.z());
  fmt::print("extent       {:.6g} {:.6g} {:.6g} (diagonal {:.6g})\n", box.extent().x(), box.extent().y(), box.extent().z(), box.diagonal());
  if (info.contains("mean_spacing")) fmt::print("mean spacing {:.6g}\n", info["mean_spacing"].get<double>());
  for (const char* kind : {"fields", "face_fields"}) {
    if (!info.contains(kind)) continue;
    const char* label = kind == std::string("fields") ? "field       " : "face field  ";
    for (const auto& f : info[kind])
      fmt::print("{} {} ({}) range [{:g}, {:g}]\n", label, f["name"].get<std::string>(), f["type"].get<std::string>(), f["min"].get<double>(),
                 f["max"].get<double>());
  }
  if (info.contains("scans"))
    for (const auto& s : info["scans"]) {
      const auto& q = s["rotation_wxyz"];
      const auto& t = s["translation"];
      fmt::print("scan         {}: {} points, pose rotation (w x y z) {:.9g} {:.9g} {:.9g} {:.9g}, translation {:.9g} {:.9g} {:.9g}\n",
                 s["name"].get<std::string>(), s["points"].get<std::size_t>(), q[0].get<double>(), q[1].get<double>(), q[2].get<double>(),
                 q[3].get<double>(), t[0].get<double>(), t[1].get<double>(), t[2].get<double>());
    }
  for (const std::string& w : warnings) fmt::print("warning      {}\n", w);
  return 0;
}

}  // namespace

Command info_command() { return {"info", "Describe a cloud or mesh: format, counts, bounding box, mean spacing, fields", run_info, info_help, {}}; }

}  // namespace pointsurf::cli
