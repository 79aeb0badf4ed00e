// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/io/polylines.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "io/detail/file_util.h"
#include "pointsurf/core/error.h"

namespace pointsurf {

void write_polylines(const std::filesystem::path& path, std::span<const Polyline> lines, const PolylineWriteOptions& options) {
  const std::string ext = io::detail::lower(path.extension().string());
  if (!options.group.empty() && options.group.size() != lines.size())
    throw UsageError(fmt::format("write_polylines: {}: {} group ids for {} polylines", path.string(), options.group.size(), lines.size()));
  if (!options.hole.empty() && options.hole.size() != lines.size())
    throw UsageError(fmt::format("write_polylines: {}: {} hole flags for {} polylines", path.string(), options.hole.size(), lines.size()));
  auto group = [&](std::size_t i) { return options.group.empty() ? std::int64_t(i) : options.group[i]; };
  if (ext == ".ply") {
    std::size_t vertices = 0, edges = 0;
    for (const Polyline& l : lines) {
      vertices += l.points.size();
      if (l.points.size() >= 2) edges += l.points.size() - 1 + (l.closed && l.points.size() > 2);
    }
    io::detail::FileWriter out(path);
    out.print("ply\nformat ascii 1.0\ncomment pointsurf polylines\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\n"
              "element edge {}\nproperty int vertex1\nproperty int vertex2\nproperty int group\nend_header\n",
              vertices, edges);
    for (const Polyline& l : lines)
      for (const Eigen::Vector3d& p : l.points) out.print("{} {} {}\n", p.x(), p.y(), p.z());
    std::size_t base = 0;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const std::size_t m = lines[i].points.size();
      for (std::size_t j = 0; j + 1 < m; ++j) out.print("{} {} {}\n", base + j, base + j + 1, group(i));
      if (lines[i].closed && m > 2) out.print("{} {} {}\n", base + m - 1, base, group(i));
      base += m;
    }
    out.close();
  } else if (ext == ".obj") {
    io::detail::FileWriter out(path);
    out.write("# pointsurf polylines\n");
    std::size_t base = 1;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const Polyline& l = lines[i];
      out.print("o polyline_{}_group_{}\n", i, group(i));
      for (const Eigen::Vector3d& p : l.points) out.print("v {} {} {}\n", p.x(), p.y(), p.z());
      if (l.points.size() >= 2) {
        out.write("l");
        for (std::size_t j = 0; j < l.points.size(); ++j) out.print(" {}", base + j);
        if (l.closed && l.points.size() > 2) out.print(" {}", base);
        out.write("\n");
      }
      base += l.points.size();
    }
    out.close();
  } else if (ext == ".geojson" || ext == ".json") {
    nlohmann::ordered_json doc;
    doc["type"] = "FeatureCollection";
    if (!options.crs.empty()) doc["crs"] = {{"type", "name"}, {"properties", {{"name", options.crs}}}};
    nlohmann::ordered_json features = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const Polyline& l = lines[i];
      nlohmann::ordered_json coords = nlohmann::ordered_json::array();
      for (const Eigen::Vector3d& p : l.points) coords.push_back({p.x(), p.y(), p.z()});
      if (l.closed && !l.points.empty()) coords.push_back({l.points.front().x(), l.points.front().y(), l.points.front().z()});
      nlohmann::ordered_json f;
      f["type"] = "Feature";
      f["properties"] = {{"id", i}, {"group", group(i)}, {"hole", !options.hole.empty() && options.hole[i] != 0}, {"closed", l.closed},
                         {"length", l.length()}};
      f["geometry"] = {{"type", "LineString"}, {"coordinates", coords}};
      features.push_back(std::move(f));
    }
    doc["features"] = std::move(features);
    io::detail::FileWriter out(path);
    out.write(doc.dump(1));
    out.write("\n");
    out.close();
  } else {
    throw UsageError(fmt::format("write_polylines: {}: unknown polyline format \"{}\" (expected .ply, .obj, .geojson)", path.string(), ext));
  }
}

}  // namespace pointsurf
