// SPDX-License-Identifier: GPL-3.0-or-later
// OFF (Geomview Object File Format): the OFF, COFF, NOFF, CNOFF and STOFF variants, read line
// by line so that errors can name the line. Vertex lines hold x y z [nx ny nz] [r g b [a]]
// [s t]; face lines hold n i0 ... i(n-1) [colour]. Face colours are not kept.
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

// What the header keyword announces.
struct OffKind {
  bool normals = false;
  bool colors = false;
  bool texture = false;
};

// Parses "[ST][C][N]OFF" (also "NCOFF", which some exporters write); false for anything
// else, including the 4D and n-dimensional variants.
bool parse_keyword(std::string_view word, OffKind& kind) {
  if (word.size() < 3 || word.substr(word.size() - 3) != "OFF") return false;
  word.remove_suffix(3);
  if (word.rfind("ST", 0) == 0) { kind.texture = true; word.remove_prefix(2); }
  for (char c : word) {
    if (c == 'C' && !kind.colors) kind.colors = true;
    else if (c == 'N' && !kind.normals) kind.normals = true;
    else return false;
  }
  return true;
}

// Yields the next line that holds something besides a comment, with the comment cut off.
bool next_content_line(TextCursor& cursor, std::string_view& line) {
  while (cursor.next_line(line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    if (line.find_first_not_of(" \t\v\f") != std::string_view::npos) return true;
  }
  return false;
}

// True when the token is written as an integer (no '.', no exponent).
bool integer_syntax(std::string_view token) { return token.find_first_of(".eE") == std::string_view::npos; }

}  // namespace

RawData read_off(const std::filesystem::path& path, const ReadOptions&) {
  const std::string name = display_name(path);
  const FileBytes file_bytes(path);
  const std::string_view text = file_bytes.view();
  TextCursor cursor(text);
  std::vector<std::string_view> tokens;
  std::string_view line;

  if (!next_content_line(cursor, line)) throw InputError(fmt::format("{}: file ends before the OFF header", name));
  split_tokens(line, tokens);
  OffKind kind;
  if (!parse_keyword(tokens[0], kind))
    throw InputError(fmt::format("{}: line {}: expected the keyword OFF, COFF, NOFF or CNOFF, got '{}'", name, cursor.line_number(), shown(tokens[0])));
  // The counts may follow the keyword on the same line.
  tokens.erase(tokens.begin());
  if (tokens.empty()) {
    if (!next_content_line(cursor, line)) throw InputError(fmt::format("{}: file ends before the vertex and face counts", name));
    split_tokens(line, tokens);
  }
  long long counts[3] = {0, 0, 0};
  if (tokens.size() < 2 || tokens.size() > 3)
    throw InputError(fmt::format("{}: line {}: expected the vertex, face and edge counts, got {} values", name, cursor.line_number(), tokens.size()));
  for (std::size_t i = 0; i < tokens.size(); ++i)
    if (!parse_number(tokens[i], counts[i]) || counts[i] < 0)
      throw InputError(fmt::format("{}: line {}: expected a non-negative count, got '{}'", name, cursor.line_number(), shown(tokens[i])));
  const auto vertex_count = static_cast<std::size_t>(counts[0]);
  const auto face_count = static_cast<std::size_t>(counts[1]);

  RawData raw;
  raw.encoding = "ascii";
  PointCloud& cloud = raw.cloud;
  // Every vertex takes at least 6 bytes ("0 0 0\n"), so a count beyond that is caught at the
  // end of the file rather than allocated up front.
  cloud.positions.reserve(std::min(vertex_count, text.size() / 6));
  if (kind.normals) cloud.normals.reserve(cloud.positions.capacity());
  std::vector<Eigen::Vector3d> colors;
  if (kind.colors) colors.reserve(cloud.positions.capacity());
  bool colors_are_integers = true;
  double max_color = 0.0;

  const std::size_t coords = 3 + (kind.normals ? 3 : 0);
  const std::size_t tail = kind.texture ? 2 : 0;
  for (std::size_t v = 0; v < vertex_count; ++v) {
    if (!next_content_line(cursor, line))
      throw InputError(fmt::format("{}: vertex {} of {}: file ends at line {}", name, v, vertex_count, cursor.line_number()));
    split_tokens(line, tokens);
    double values[6];
    if (tokens.size() < coords)
      throw InputError(fmt::format("{}: line {} (vertex {}): expected {} {}, got {}", name, cursor.line_number(), v, coords,
                                   kind.normals ? "values (x y z nx ny nz)" : "coordinates", tokens.size()));
    for (std::size_t k = 0; k < coords; ++k)
      if (!parse_number(tokens[k], values[k]))
        throw InputError(fmt::format("{}: line {} (vertex {}): expected a number, got '{}'", name, cursor.line_number(), v, shown(tokens[k])));
    cloud.positions.emplace_back(values[0], values[1], values[2]);
    if (kind.normals) cloud.normals.emplace_back(values[3], values[4], values[5]);
    if (kind.colors) {
      const std::size_t extra = tokens.size() - coords - std::min(tail, tokens.size() - coords);
      if (extra != 3 && extra != 4)
        throw InputError(fmt::format("{}: line {} (vertex {}): expected 3 or 4 colour values after the {}, got {}", name,
                                     cursor.line_number(), v, kind.normals ? "normal" : "coordinates", extra));
      Eigen::Vector3d c;
      for (std::size_t k = 0; k < 3; ++k) {
        const std::string_view t = tokens[coords + k];
        if (!parse_number(t, c[static_cast<int>(k)]))
          throw InputError(fmt::format("{}: line {} (vertex {}): expected a colour value, got '{}'", name, cursor.line_number(), v, shown(t)));
        colors_are_integers = colors_are_integers && integer_syntax(t);
        max_color = std::max(max_color, c[static_cast<int>(k)]);
      }
      colors.push_back(c);
    }
  }
  if (kind.colors) {
    // Colours are either integers 0..255 or floats 0..1; integers, or any value above 1,
    // mean the 8-bit range.
    const double full = colors_are_integers || max_color > 1.0 ? 255.0 : 1.0;
    cloud.colors.reserve(colors.size());
    for (const Eigen::Vector3d& c : colors) cloud.colors.push_back((c.cast<float>() / static_cast<float>(full)).cwiseMax(0.0f).cwiseMin(1.0f));
  }

  raw.polygons.reserve(std::min(face_count, text.size() / 4));
  for (std::size_t f = 0; f < face_count; ++f) {
    if (!next_content_line(cursor, line))
      throw InputError(fmt::format("{}: face {} of {}: file ends at line {}", name, f, face_count, cursor.line_number()));
    split_tokens(line, tokens);
    long long corners = 0;
    if (!parse_number(tokens[0], corners) || corners < 0)
      throw InputError(fmt::format("{}: line {} (face {}): expected the number of indices, got '{}'", name, cursor.line_number(), f, shown(tokens[0])));
    if (tokens.size() - 1 < static_cast<std::size_t>(corners))
      throw InputError(fmt::format("{}: line {} (face {}): {} indices announced, {} given", name, cursor.line_number(), f, corners,
                                   tokens.size() - 1));
    std::vector<int>& polygon = raw.polygons.emplace_back();
    polygon.reserve(static_cast<std::size_t>(corners));
    for (long long k = 1; k <= corners; ++k) {
      long long index = 0;
      if (!parse_number(tokens[static_cast<std::size_t>(k)], index))
        throw InputError(fmt::format("{}: line {} (face {}): expected a vertex index, got '{}'", name, cursor.line_number(), f,
                                     shown(tokens[static_cast<std::size_t>(k)])));
      if (index < 0 || static_cast<std::size_t>(index) >= vertex_count)
        throw InputError(fmt::format("{}: line {} (face {}): vertex index {} out of range [0, {})", name, cursor.line_number(), f, index,
                                     vertex_count));
      polygon.push_back(static_cast<int>(index));
    }
  }
  return raw;
}

// Writes OFF, with the "N" prefix when the cloud has normals and "C" when it has colours
// (written as RGBA integers 0..255, which every OFF reader accepts). Scalar fields have no
// place in OFF and are dropped.
void write_off(const std::filesystem::path& path, const PointCloud& cloud, const std::vector<Triangle>& triangles,
               const WriteOptions& options) {
  FileWriter out(path);
  const bool colors = cloud.has_colors();
  const bool normals = cloud.has_normals();
  out.write(fmt::format("{}{}OFF\n{} {} 0\n", colors ? "C" : "", normals ? "N" : "", cloud.size(), triangles.size()));
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vector3d& p = cloud.positions[i];
    out.write_double(p.x(), options.precision);
    out.write(" ");
    out.write_double(p.y(), options.precision);
    out.write(" ");
    out.write_double(p.z(), options.precision);
    if (normals) {
      const Vector3d& n = cloud.normals[i];
      for (int k = 0; k < 3; ++k) {
        out.write(" ");
        out.write_double(n[k], options.precision);
      }
    }
    if (colors) {
      const Vector3f& c = cloud.colors[i];
      auto byte = [](float v) { return static_cast<int>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
      out.print(" {} {} {} 255", byte(c.x()), byte(c.y()), byte(c.z()));
    }
    out.write("\n");
  }
  for (const Triangle& t : triangles) out.print("3 {} {} {}\n", t[0], t[1], t[2]);
  out.close();
}

}  // namespace pointsurf::io::detail
