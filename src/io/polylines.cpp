// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/io/polylines.h"

#include <algorithm>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "io/detail/file_util.h"
#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

// Whether a polyline bounds an area: flagged closed, or ending where it starts, with at least
// three distinct vertices.
bool is_ring(const Polyline& l) {
  const bool repeated = l.points.size() >= 2 && l.points.front() == l.points.back();
  return (l.closed || repeated) && l.points.size() - (repeated ? 1 : 0) >= 3;
}

// The GeoJSON ring of a closed polyline: its vertices counter-clockwise (or clockwise) seen from
// above in x, y, starting at its first vertex and ending with it again (RFC 7946 3.1.6). A ring
// without area in x, y (a vertical wall's) keeps its order.
nlohmann::ordered_json geojson_ring(const Polyline& l, bool counter_clockwise) {
  std::vector<Eigen::Vector3d> ring = l.points;
  if (ring.front() == ring.back()) ring.pop_back();
  // Twice the signed area, relative to the first vertex so that 1e6 m coordinates keep digits.
  double area = 0.0;
  for (std::size_t i = 1; i + 1 < ring.size(); ++i) {
    const Eigen::Vector3d a = ring[i] - ring[0], b = ring[i + 1] - ring[0];
    area += a.x() * b.y() - a.y() * b.x();
  }
  if (counter_clockwise ? area < 0.0 : area > 0.0) std::reverse(ring.begin() + 1, ring.end());
  ring.push_back(ring.front());
  nlohmann::ordered_json coords = nlohmann::ordered_json::array();
  for (const Eigen::Vector3d& p : ring) coords.push_back({p.x(), p.y(), p.z()});
  return coords;
}

}  // namespace

void write_polylines(const std::filesystem::path& path, std::span<const Polyline> lines, const PolylineWriteOptions& options) {
  const std::string ext = io::detail::lower(path.extension().string());
  if (!options.group.empty() && options.group.size() != lines.size())
    throw UsageError(fmt::format("write_polylines: {}: {} group ids for {} polylines", path.string(), options.group.size(), lines.size()));
  if (!options.outer.empty() && options.outer.size() != lines.size())
    throw UsageError(fmt::format("write_polylines: {}: {} outer indices for {} polylines", path.string(), options.outer.size(), lines.size()));
  auto outer = [&](std::size_t i) { return options.outer.empty() ? std::int64_t(-1) : options.outer[i]; };
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::int64_t o = outer(i);
    if (o < 0) continue;
    if (o >= std::int64_t(lines.size()) || o == std::int64_t(i) || outer(o) >= 0 || !is_ring(lines[i]) || !is_ring(lines[o]))
      throw UsageError(fmt::format("write_polylines: {}: polyline {} is a hole of polyline {}, which is not a closed outer polyline of {}",
                                   path.string(), i, o, lines.size()));
  }
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
      if (outer(i) >= 0) continue;  // an inner ring of its outer polyline's Polygon
      const Polyline& l = lines[i];
      nlohmann::ordered_json f;
      f["type"] = "Feature";
      if (is_ring(l)) {
        nlohmann::ordered_json rings = nlohmann::ordered_json::array({geojson_ring(l, true)});
        double length = l.length();
        for (std::size_t j = 0; j < lines.size(); ++j)
          if (outer(j) == std::int64_t(i)) rings.push_back(geojson_ring(lines[j], false)), length += lines[j].length();
        f["properties"] = {{"id", i}, {"group", group(i)}, {"closed", true}, {"holes", rings.size() - 1}, {"length", length}};
        f["geometry"] = {{"type", "Polygon"}, {"coordinates", std::move(rings)}};
      } else {
        nlohmann::ordered_json coords = nlohmann::ordered_json::array();
        for (const Eigen::Vector3d& p : l.points) coords.push_back({p.x(), p.y(), p.z()});
        if (l.closed && !l.points.empty()) coords.push_back({l.points.front().x(), l.points.front().y(), l.points.front().z()});
        f["properties"] = {{"id", i}, {"group", group(i)}, {"closed", l.closed}, {"holes", 0}, {"length", l.length()}};
        f["geometry"] = {{"type", "LineString"}, {"coordinates", std::move(coords)}};
      }
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
