// SPDX-License-Identifier: GPL-3.0-or-later
// STL, binary (80-byte header, uint32 facet count, 50 bytes per facet of float32) and ascii
// (solid / facet normal / outer loop / vertex x3 / endloop / endfacet / endsolid).
// STL repeats each corner in every facet that uses it; the reader merges exactly equal
// corners so that the result is an indexed mesh. Facet normals are not kept: the triangles'
// winding gives them back.
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

constexpr std::size_t kBinaryHeader = 84;
constexpr std::size_t kFacetBytes = 50;

struct PositionHash {
  std::size_t operator()(const Vector3d& p) const noexcept {
    std::size_t h = 0;
    for (int k = 0; k < 3; ++k) {
      std::uint64_t bits;
      std::memcpy(&bits, &p[k], sizeof(bits));
      h ^= std::hash<std::uint64_t>{}(bits) + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
    }
    return h;
  }
};

// Gives each distinct position one vertex index.
class VertexMerger {
public:
  VertexMerger(PointCloud& cloud, std::size_t expected) : cloud_(cloud) {
    index_.reserve(expected);
    cloud_.positions.reserve(expected);
  }
  int add(Vector3d p) {
    // -0.0 and 0.0 compare equal but hash differently; adding +0.0 turns -0.0 into +0.0.
    p += Vector3d::Zero();
    const auto [it, inserted] = index_.try_emplace(p, static_cast<int>(cloud_.positions.size()));
    if (inserted) cloud_.positions.push_back(p);
    return it->second;
  }

private:
  PointCloud& cloud_;
  std::unordered_map<Vector3d, int, PositionHash> index_;
};

bool starts_with_solid(std::string_view bytes) {
  const std::size_t i = bytes.find_first_not_of(" \t\r\n");
  return i != std::string_view::npos && bytes.substr(i, 5) == "solid";
}

RawData read_binary(std::string_view bytes, const std::string& name) {
  if (bytes.size() < kBinaryHeader)
    throw InputError(fmt::format("{}: binary STL: file ends at byte {}, inside the 84-byte header", name, bytes.size()));
  const std::uint64_t count = load_value<std::uint32_t>(bytes.data() + 80);
  const std::size_t available = (bytes.size() - kBinaryHeader) / kFacetBytes;
  if (count > available)
    throw InputError(fmt::format("{}: binary STL: facet {} of {}: file ends at byte {}", name, available, count, bytes.size()));
  RawData raw;
  raw.encoding = "binary_little_endian";
  raw.triangles.reserve(count);
  // A closed mesh has about half as many vertices as facets.
  VertexMerger merger(raw.cloud, count / 2 + 3);
  const char* facet = bytes.data() + kBinaryHeader;
  for (std::size_t f = 0; f < count; ++f, facet += kFacetBytes) {
    Triangle t;
    for (int c = 0; c < 3; ++c) {
      const char* p = facet + 12 + 12 * c;  // after the facet normal
      t[c] = merger.add(Vector3d(load_value<float>(p), load_value<float>(p + 4), load_value<float>(p + 8)));
    }
    raw.triangles.push_back(t);
  }
  return raw;
}

RawData read_ascii(std::string_view text, const std::string& name) {
  RawData raw;
  raw.encoding = "ascii";
  // An ascii facet takes well over 100 bytes; this bounds the reservation by the file size.
  VertexMerger merger(raw.cloud, text.size() / 256);
  TextCursor cursor(text);
  std::vector<std::string_view> tokens;
  std::string_view line;

  // The parser walks this cycle of expected keywords; "solid" and "endsolid" may repeat.
  enum class Expect { Solid, FacetOrEnd, OuterLoop, Vertex, EndLoop, EndFacet };
  Expect expect = Expect::Solid;
  Triangle t;
  int corner = 0;
  auto fail = [&](std::string_view expected) {
    const std::string got = tokens.empty() ? std::string("an empty line") : fmt::format("'{}'", shown(tokens[0]));
    throw InputError(fmt::format("{}: line {}: expected {}, got {}", name, cursor.line_number(), expected, got));
  };
  auto parse_vertex = [&]() {
    if (tokens.size() != 4) throw InputError(fmt::format("{}: line {}: vertex: expected 3 coordinates, got {}", name, cursor.line_number(), tokens.size() - 1));
    double v[3];
    for (int k = 0; k < 3; ++k)
      if (!parse_number(tokens[static_cast<std::size_t>(k) + 1], v[k]))
        throw InputError(fmt::format("{}: line {}: vertex: expected a number, got '{}'", name, cursor.line_number(), shown(tokens[static_cast<std::size_t>(k) + 1])));
    return Vector3d(v[0], v[1], v[2]);
  };

  while (cursor.next_line(line)) {
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    const std::string_view key = tokens[0];
    switch (expect) {
      case Expect::Solid:
        if (key != "solid") fail("'solid'");
        expect = Expect::FacetOrEnd;
        break;
      case Expect::FacetOrEnd:
        if (key == "endsolid") expect = Expect::Solid;
        else if (key == "facet") expect = Expect::OuterLoop;
        else fail("'facet' or 'endsolid'");
        break;
      case Expect::OuterLoop:
        if (key != "outer" || tokens.size() < 2 || tokens[1] != "loop") fail("'outer loop'");
        expect = Expect::Vertex;
        corner = 0;
        break;
      case Expect::Vertex:
        if (key != "vertex") fail(fmt::format("'vertex x y z' (corner {} of 3)", corner + 1));
        t[corner] = merger.add(parse_vertex());
        if (++corner == 3) expect = Expect::EndLoop;
        break;
      case Expect::EndLoop:
        if (key != "endloop") fail("'endloop' after 3 vertices");
        expect = Expect::EndFacet;
        break;
      case Expect::EndFacet:
        if (key != "endfacet") fail("'endfacet'");
        raw.triangles.push_back(t);
        expect = Expect::FacetOrEnd;
        break;
    }
  }
  if (expect != Expect::Solid) {
    // Many exporters end the file without "endsolid"; a file cut inside a facet is broken.
    if (expect != Expect::FacetOrEnd)
      throw InputError(fmt::format("{}: line {}: file ends inside facet {}", name, cursor.line_number(), raw.triangles.size()));
    raw.warnings.push_back(fmt::format("{}: ascii STL without 'endsolid'", name));
  }
  return raw;
}


Vector3f facet_normal(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Vector3f((n / len).cast<float>()) : Vector3f::Zero();
}

}  // namespace

RawData read_stl(const std::filesystem::path& path, const ReadOptions&) {
  const std::string name = display_name(path);
  const FileBytes file_bytes(path);
  const std::string_view bytes = file_bytes.view();
  // The size test comes first: many binary exporters start their header with "solid" too.
  if (bytes.size() >= kBinaryHeader &&
      kBinaryHeader + kFacetBytes * static_cast<std::uint64_t>(load_value<std::uint32_t>(bytes.data() + 80)) == bytes.size())
    return read_binary(bytes, name);
  if (starts_with_solid(bytes) && bytes.find('\0') == std::string::npos) return read_ascii(bytes, name);
  return read_binary(bytes, name);
}

// Binary by default, ascii with options.ascii. Facet normals are computed from the corners.
// Binary STL stores float32 by definition; ascii coordinates keep full double precision.
void write_stl(const std::filesystem::path& path, const PointCloud& cloud, const std::vector<Triangle>& triangles,
               const WriteOptions& options) {
  const std::string name = display_name(path);
  if (triangles.empty()) throw UsageError(fmt::format("{}: STL holds triangles only; this has no triangles", name));
  if (triangles.size() > std::numeric_limits<std::uint32_t>::max())
    throw UsageError(fmt::format("{}: binary STL holds at most 4294967295 triangles, this has {}", name, triangles.size()));
  const auto& p = cloud.positions;
  FileWriter out(path);
  if (options.ascii) {
    out.write("solid pointsurf\n");
    for (const Triangle& t : triangles) {
      const Vector3f n = facet_normal(p[t[0]], p[t[1]], p[t[2]]);
      out.print("  facet normal {} {} {}\n    outer loop\n", n.x(), n.y(), n.z());
      for (int c = 0; c < 3; ++c) {
        out.write("      vertex");
        for (int k = 0; k < 3; ++k) {
          out.write(" ");
          out.write_double(p[t[c]][k], options.precision);
        }
        out.write("\n");
      }
      out.write("    endloop\n  endfacet\n");
    }
    out.write("endsolid pointsurf\n");
  } else {
    // The header must not start with "solid", or some readers take the file for ascii.
    std::string header = "binary STL written by pointsurf";
    header.resize(80, ' ');
    out.write(header);
    out.write_value<std::uint32_t>(static_cast<std::uint32_t>(triangles.size()));
    for (const Triangle& t : triangles) {
      const Vector3f n = facet_normal(p[t[0]], p[t[1]], p[t[2]]);
      for (int k = 0; k < 3; ++k) out.write_value<float>(n[k]);
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) out.write_value<float>(static_cast<float>(p[t[c]][k]));
      out.write_value<std::uint16_t>(0);
    }
  }
  out.close();
}

}  // namespace pointsurf::io::detail
