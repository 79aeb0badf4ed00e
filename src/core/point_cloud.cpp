// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/point_cloud.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

namespace {

// The GeoTIFF key `id` of a key directory (unsigned 16-bit words: version, revision, minor
// revision, key count, then per key id, location, count, value) when its value is inline; 0 else.
int geokey_value(const std::vector<std::uint8_t>& dir, int id) {
  auto word = [&](std::size_t k) { return dir[2 * k] | (dir[2 * k + 1] << 8); };
  if (dir.size() < 8) return 0;
  const std::size_t keys = static_cast<std::size_t>(word(3));
  for (std::size_t k = 0; k < keys && 2 * (4 * k + 8) <= dir.size(); ++k)
    if (word(4 * k + 4) == id && word(4 * k + 5) == 0) return word(4 * k + 7);
  return 0;
}

// The name in `KEYWORD["name"` for the first CRS keyword of a WKT string.
std::string wkt_name(const std::string& wkt) {
  std::size_t best = std::string::npos;
  for (const char* key : {"COMPD_CS[", "COMPOUNDCRS[", "PROJCRS[", "PROJCS[", "GEOGCRS[", "GEOGCS[", "GEODCRS[", "GEOCCS[", "VERT_CS[", "VERTCRS["}) {
    const std::size_t at = wkt.find(key);
    if (at != std::string::npos && (best == std::string::npos || at < best)) best = at;
  }
  if (best == std::string::npos) return {};
  const std::size_t open = wkt.find('"', best), close = open == std::string::npos ? open : wkt.find('"', open + 1);
  return close == std::string::npos ? std::string() : wkt.substr(open + 1, close - open - 1);
}

}  // namespace

int CoordinateSystem::epsg() const {
  if (!wkt.empty()) {
    // The outermost authority closes the WKT, so it is the last one.
    const std::size_t at = wkt.rfind("\"EPSG\"");
    if (at == std::string::npos) return 0;
    std::size_t i = at + 6;
    while (i < wkt.size() && (wkt[i] == ',' || wkt[i] == ' ' || wkt[i] == '"')) ++i;
    int code = 0;
    for (; i < wkt.size() && wkt[i] >= '0' && wkt[i] <= '9' && code < 10000000; ++i) code = code * 10 + (wkt[i] - '0');
    return code;
  }
  const int projected = geokey_value(geokeys, 3072);
  return projected != 0 && projected != 32767 ? projected : geokey_value(geokeys, 2048);
}

std::string CoordinateSystem::describe() const {
  if (empty()) return {};
  const int code = epsg();
  const std::string epsg_text = code > 0 && code != 32767 ? fmt::format("EPSG:{}", code) : std::string();
  if (wkt.empty()) return epsg_text.empty() ? std::string("GeoTIFF keys (user-defined)") : epsg_text + " (GeoTIFF keys)";
  const std::string name = wkt_name(wkt);
  if (name.empty()) return !epsg_text.empty() ? epsg_text : wkt.size() <= 60 ? wkt : std::string("WKT");
  return epsg_text.empty() ? name : fmt::format("{} ({})", name, epsg_text);
}

void PointCloud::validate() const {
  const std::size_t n = size();
  if (!normals.empty() && normals.size() != n)
    throw InputError(fmt::format("point cloud: {} normals for {} points", normals.size(), n));
  if (!colors.empty() && colors.size() != n)
    throw InputError(fmt::format("point cloud: {} colours for {} points", colors.size(), n));
  for (const ScalarField& f : fields)
    if (f.values.size() != n)
      throw InputError(fmt::format("point cloud: field '{}' has {} values for {} points", f.name, f.values.size(), n));
}

PointCloud PointCloud::select(std::span<const std::size_t> indices) const {
  PointCloud out;
  out.crs = crs;
  out.positions.reserve(indices.size());
  for (std::size_t i : indices) out.positions.push_back(positions[i]);
  if (has_normals()) {
    out.normals.reserve(indices.size());
    for (std::size_t i : indices) out.normals.push_back(normals[i]);
  }
  if (has_colors()) {
    out.colors.reserve(indices.size());
    for (std::size_t i : indices) out.colors.push_back(colors[i]);
  }
  for (const ScalarField& f : fields) {
    ScalarField& g = out.fields.add(f.name, 0, f.type);
    g.values.reserve(indices.size());
    for (std::size_t i : indices) g.values.push_back(f.values[i]);
  }
  return out;
}

void PointCloud::append(const PointCloud& other) {
  if (&other == this) {  // inserting a vector's own range into itself is undefined
    const PointCloud copy = other;
    append(copy);
    return;
  }
  if (crs.empty()) crs = other.crs;
  const std::size_t n0 = size(), n1 = other.size();
  const bool normals_out = has_normals() || other.has_normals();
  const bool colors_out = has_colors() || other.has_colors();
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  if (normals_out) {
    normals.resize(n0, Vector3d::Zero());
    if (other.has_normals()) normals.insert(normals.end(), other.normals.begin(), other.normals.end());
    else normals.resize(n0 + n1, Vector3d::Zero());
  }
  if (colors_out) {
    colors.resize(n0, Vector3f::Zero());
    if (other.has_colors()) colors.insert(colors.end(), other.colors.begin(), other.colors.end());
    else colors.resize(n0 + n1, Vector3f::Zero());
  }
  for (ScalarField& f : fields) {
    const ScalarField* g = other.fields.find(f.name);
    if (g) f.values.insert(f.values.end(), g->values.begin(), g->values.end());
    else f.values.resize(n0 + n1, 0.0);
  }
  for (const ScalarField& g : other.fields) {
    if (fields.contains(g.name)) continue;
    ScalarField& f = fields.add(g.name, n0, g.type);
    f.values.insert(f.values.end(), g.values.begin(), g.values.end());
  }
}

BoundingBox bounding_box(std::span<const Vector3d> points) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), 1 << 14), BoundingBox{},
      [&](const tbb::blocked_range<std::size_t>& r, BoundingBox box) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) box.extend(points[i]);
        return box;
      },
      [](BoundingBox a, const BoundingBox& b) {
        if (!b.empty()) { a.extend(b.min); a.extend(b.max); }
        return a;
      });
}

}  // namespace pointsurf
