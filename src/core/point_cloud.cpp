// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/point_cloud.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <set>

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

// One node of a WKT string: `KEYWORD[value, ..., CHILD[...], ...]`, with `[]` or `()` as
// brackets. Values keep their text (quoted ones without the quotes, a doubled `""` as one quote).
struct WktNode {
  std::string keyword;
  std::vector<std::string> values;
  std::vector<WktNode> children;
};

// Deeper nesting than any CRS has (a compound of projected CRSs nests about 6 deep) is not
// followed: the rest is dropped, so a crafted WKT cannot exhaust the stack.
constexpr int kMaxWktDepth = 32;

// Reads the node that starts at `at` (after blanks) and moves `at` past it. A node that ends
// early (a truncated WKT) keeps what was read.
WktNode read_wkt_node(const std::string& wkt, std::size_t& at, int depth = 0) {
  auto blank = [&] { while (at < wkt.size() && std::isspace(static_cast<unsigned char>(wkt[at]))) ++at; };
  WktNode node;
  blank();
  while (at < wkt.size() && (std::isalnum(static_cast<unsigned char>(wkt[at])) || wkt[at] == '_')) node.keyword += wkt[at++];
  blank();
  if (at >= wkt.size() || (wkt[at] != '[' && wkt[at] != '(')) return node;
  ++at;
  while (at < wkt.size()) {
    blank();
    if (at >= wkt.size()) break;
    const char c = wkt[at];
    if (c == ']' || c == ')') {
      ++at;
      break;
    }
    if (c == ',') {
      ++at;
    } else if (c == '"') {
      std::string text;
      for (++at; at < wkt.size(); ++at) {
        if (wkt[at] != '"') text += wkt[at];
        else if (at + 1 < wkt.size() && wkt[at + 1] == '"') text += wkt[++at];
        else break;
      }
      ++at;
      node.values.push_back(std::move(text));
    } else {
      // A number, an enumeration (NORTH) or a child keyword: a child when a bracket follows.
      const std::size_t start = at;
      while (at < wkt.size() && !std::strchr(",[]()\"", wkt[at]) && !std::isspace(static_cast<unsigned char>(wkt[at]))) ++at;
      std::size_t next = at;
      while (next < wkt.size() && std::isspace(static_cast<unsigned char>(wkt[next]))) ++next;
      if (next < wkt.size() && (wkt[next] == '[' || wkt[next] == '(')) {
        if (depth >= kMaxWktDepth) {
          at = wkt.size();
          break;
        }
        at = start;
        node.children.push_back(read_wkt_node(wkt, at, depth + 1));
      } else if (at == start) {
        ++at;  // a stray quote or bracket: skip it
      } else {
        node.values.push_back(wkt.substr(start, at - start));
      }
    }
  }
  return node;
}

// The CRS a WKT string describes: its outermost node when that is a CRS keyword (WKT1 or
// WKT2), the source CRS of a WKT2 BOUNDCRS; nullptr for anything else.
const WktNode* wkt_crs(const WktNode& root) {
  static const std::set<std::string> crs_keywords = {
      "PROJCS", "PROJCRS", "PROJECTEDCRS", "GEOGCS", "GEOGCRS", "GEOGRAPHICCRS", "GEODCRS", "GEODETICCRS", "GEOCCS", "COMPD_CS",
      "COMPOUNDCRS", "VERT_CS", "VERTCRS", "VERTICALCRS", "LOCAL_CS", "ENGCRS", "ENGINEERINGCRS"};
  if (root.keyword == "BOUNDCRS") {
    for (const WktNode& child : root.children)
      if (child.keyword == "SOURCECRS" && !child.children.empty()) return wkt_crs(child.children.front());
    return nullptr;
  }
  return crs_keywords.contains(root.keyword) ? &root : nullptr;
}

// The EPSG code of the CRS's own AUTHORITY["EPSG","code"] (WKT1) or ID["EPSG",code] (WKT2):
// a direct child of the CRS node, not one of its unit, datum, axis or base CRS; 0 if none.
int wkt_epsg(const WktNode& crs) {
  for (const WktNode& child : crs.children) {
    if ((child.keyword != "AUTHORITY" && child.keyword != "ID") || child.values.size() < 2) continue;
    std::string authority = child.values[0];
    for (char& c : authority) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    const std::string& code = child.values[1];
    const bool digits = !code.empty() && code.size() <= 9 && std::all_of(code.begin(), code.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (authority == "EPSG" && digits) return std::stoi(code);
  }
  return 0;
}

}  // namespace

int CoordinateSystem::epsg() const {
  if (!wkt.empty()) {
    std::size_t at = 0;
    const WktNode root = read_wkt_node(wkt, at);
    const WktNode* crs = wkt_crs(root);
    return crs != nullptr ? wkt_epsg(*crs) : 0;
  }
  const int projected = geokey_value(geokeys, 3072);
  return projected != 0 && projected != 32767 ? projected : geokey_value(geokeys, 2048);
}

std::string CoordinateSystem::describe() const {
  if (empty()) return {};
  const int code = epsg();
  const std::string epsg_text = code > 0 && code != 32767 ? fmt::format("EPSG:{}", code) : std::string();
  if (wkt.empty()) return epsg_text.empty() ? std::string("GeoTIFF keys (user-defined)") : epsg_text + " (GeoTIFF keys)";
  std::size_t at = 0;
  const WktNode root = read_wkt_node(wkt, at);
  const WktNode* crs = wkt_crs(root);
  const std::string name = crs != nullptr && !crs->values.empty() ? crs->values.front() : std::string();
  // A WKT without a code of its own is still the CRS: say so rather than show nothing.
  if (name.empty()) return !epsg_text.empty() ? epsg_text : fmt::format("{} (no EPSG code)", wkt.size() <= 60 ? wkt : std::string("WKT"));
  return fmt::format("{} ({})", name, epsg_text.empty() ? "no EPSG code" : epsg_text);
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
  out.grid = grid;
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
  if (empty() && grid.empty()) grid = other.grid;
  else if (grid != other.grid && !other.empty()) grid = {};
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
