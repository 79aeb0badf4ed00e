// SPDX-License-Identifier: GPL-3.0-or-later
// Wavefront OBJ: vertices (with the common "v x y z r g b" colour extension), vertex normals
// and polygonal faces in every index form (v, v/vt, v//vn, v/vt/vn, negative = relative).
// Texture coordinates, materials, groups, lines and points are not kept.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

// Resolves a 1-based or negative (relative to the `defined` elements so far) OBJ index to a
// 0-based one; throws naming the line when it is 0 or out of range.
std::size_t resolve_index(std::string_view token, std::size_t defined, const char* what, const char* plural, const std::string& name,
                          std::size_t line) {
  long long index = 0;
  if (!parse_number(token, index))
    throw InputError(fmt::format("{}: line {}: expected a {} index, got '{}'", name, line, what, shown(token)));
  if (index == 0) throw InputError(fmt::format("{}: line {}: {} index 0: OBJ indices start at 1", name, line, what));
  const long long resolved = index > 0 ? index - 1 : static_cast<long long>(defined) + index;
  if (resolved < 0 || resolved >= static_cast<long long>(defined))
    throw InputError(fmt::format("{}: line {}: {} index {} out of range: {} {} defined so far", name, line, what, index, defined, plural));
  return static_cast<std::size_t>(resolved);
}

}  // namespace

RawData read_obj(const std::filesystem::path& path, const ReadOptions&) {
  const std::string name = display_name(path);
  const FileBytes file_bytes(path);
  const std::string_view text = file_bytes.view();
  TextCursor cursor(text);
  std::vector<std::string_view> tokens;
  std::string_view line;

  RawData raw;
  raw.encoding = "ascii";
  PointCloud& cloud = raw.cloud;
  std::vector<Vector3d> file_normals;
  std::vector<Eigen::Vector3d> colors;  // raw values, scaled once the range is known
  std::vector<std::size_t> color_lines;
  // Per vertex, from the face references: the first normal referenced, and the sum of the
  // unit normals when faces disagree (a flat-shaded cube), whose direction is then used.
  std::vector<long long> first_normal;
  std::vector<Vector3d> normal_sums;
  std::vector<bool> mixed_normals;
  bool faces_reference_normals = false;

  while (cursor.next_line(line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    const std::string_view key = tokens[0];
    const std::size_t values = tokens.size() - 1;
    if (key == "v") {
      // x y z, x y z w, x y z r g b, or x y z w r g b.
      if (values < 3)
        throw InputError(fmt::format("{}: line {}: vertex: expected 3 coordinates, got {}", name, cursor.line_number(), values));
      if (values != 3 && values != 4 && values != 6 && values != 7)
        throw InputError(fmt::format("{}: line {}: vertex: expected x y z [w] [r g b], got {} values", name, cursor.line_number(), values));
      double v[7];
      for (std::size_t k = 0; k < values; ++k)
        if (!parse_number(tokens[k + 1], v[k]))
          throw InputError(fmt::format("{}: line {}: vertex: expected a number, got '{}'", name, cursor.line_number(), shown(tokens[k + 1])));
      cloud.positions.emplace_back(v[0], v[1], v[2]);
      if (values >= 6) {
        const std::size_t c = values - 3;
        // Vertices before the first coloured one get black, like PointCloud::append does.
        colors.resize(cloud.positions.size() - 1, Eigen::Vector3d::Zero());
        colors.emplace_back(v[c], v[c + 1], v[c + 2]);
      } else if (!colors.empty()) {
        colors.emplace_back(Eigen::Vector3d::Zero());
      }
    } else if (key == "vn") {
      if (values != 3)
        throw InputError(fmt::format("{}: line {}: vertex normal: expected 3 values, got {}", name, cursor.line_number(), values));
      double v[3];
      for (std::size_t k = 0; k < 3; ++k)
        if (!parse_number(tokens[k + 1], v[k]))
          throw InputError(fmt::format("{}: line {}: vertex normal: expected a number, got '{}'", name, cursor.line_number(), shown(tokens[k + 1])));
      file_normals.emplace_back(v[0], v[1], v[2]);
    } else if (key == "f") {
      if (values < 3)
        throw InputError(fmt::format("{}: line {}: face: expected at least 3 vertices, got {}", name, cursor.line_number(), values));
      std::vector<int>& polygon = raw.polygons.emplace_back();
      polygon.reserve(values);
      for (std::size_t k = 1; k <= values; ++k) {
        const std::string_view corner = tokens[k];
        const std::size_t slash = corner.find('/');
        const std::size_t v = resolve_index(corner.substr(0, slash), cloud.size(), "vertex", "vertices", name, cursor.line_number());
        polygon.push_back(static_cast<int>(v));
        if (slash == std::string_view::npos) continue;
        const std::size_t slash2 = corner.find('/', slash + 1);
        if (slash2 == std::string_view::npos || slash2 + 1 == corner.size()) continue;  // v/vt or v/vt/
        const std::size_t n = resolve_index(corner.substr(slash2 + 1), file_normals.size(), "normal", "normals", name, cursor.line_number());
        if (first_normal.size() < cloud.size()) {
          first_normal.resize(cloud.size(), -1);
          normal_sums.resize(cloud.size(), Vector3d::Zero());
          mixed_normals.resize(cloud.size(), false);
        }
        if (first_normal[v] < 0) first_normal[v] = static_cast<long long>(n);
        else if (file_normals[n] != file_normals[static_cast<std::size_t>(first_normal[v])]) mixed_normals[v] = true;
        normal_sums[v] += file_normals[n].normalized();
        faces_reference_normals = true;
      }
    }
    // vt, vp, l, p, o, g, s, usemtl, mtllib and the free-form geometry keywords are skipped.
  }

  const std::size_t n = cloud.size();
  if (faces_reference_normals) {
    first_normal.resize(n, -1);
    cloud.normals.resize(n, Vector3d::Zero());
    for (std::size_t i = 0; i < n; ++i) {
      if (first_normal[i] < 0) continue;  // no face gives this vertex a normal: zero
      if (!mixed_normals[i]) {
        cloud.normals[i] = file_normals[static_cast<std::size_t>(first_normal[i])];
        continue;
      }
      const double len = normal_sums[i].norm();
      if (len > 0) cloud.normals[i] = normal_sums[i] / len;
    }
  } else if (!file_normals.empty() && file_normals.size() == n) {
    // No face says which normal goes where (a point cloud): the i-th normal is the i-th vertex's.
    cloud.normals = std::move(file_normals);
  } else if (!file_normals.empty()) {
    raw.warnings.push_back(fmt::format("{}: {} vertex normals ignored: no face refers to them and there are {} vertices", name,
                                       file_normals.size(), n));
  }
  if (!colors.empty()) {
    // The extension stores floats 0..1, but some exporters write 0..255.
    double max_color = 0;
    for (const auto& c : colors) max_color = std::max(max_color, c.maxCoeff());
    const double full = max_color > 1.0 ? 255.0 : 1.0;
    cloud.colors.reserve(n);
    for (const auto& c : colors) cloud.colors.push_back((c.cast<float>() / static_cast<float>(full)).cwiseMax(0.0f).cwiseMin(1.0f));
  }
  return raw;
}

// Writes "v x y z [r g b]" lines (colours as floats 0..1), "vn" lines when the cloud has
// normals, then "f" lines with 1-based indices ("f a//a b//b c//c" with normals). Scalar
// fields have no place in OBJ and are dropped.
void write_obj(const std::filesystem::path& path, const PointCloud& cloud, const std::vector<Triangle>& triangles,
               const WriteOptions& options) {
  FileWriter out(path);
  out.write("# written by pointsurf\n");
  const bool colors = cloud.has_colors();
  const bool normals = cloud.has_normals();
  auto write_values = [&](const char* key, const auto& v, int precision) {
    out.write(key);
    for (int k = 0; k < 3; ++k) {
      out.write(" ");
      out.write_double(static_cast<double>(v[k]), precision);
    }
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    write_values("v", cloud.positions[i], options.precision);
    if (colors) {
      const Vector3f c = cloud.colors[i].cwiseMax(0.0f).cwiseMin(1.0f);
      // Nine digits give back the same float.
      for (int k = 0; k < 3; ++k) {
        out.write(" ");
        out.write_double(static_cast<double>(c[k]), 9);
      }
    }
    out.write("\n");
  }
  if (normals)
    for (const Vector3d& nrm : cloud.normals) {
      write_values("vn", nrm, options.precision);
      out.write("\n");
    }
  for (const Triangle& t : triangles) {
    if (normals) out.print("f {0}//{0} {1}//{1} {2}//{2}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    else out.print("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  out.close();
}

}  // namespace pointsurf::io::detail
