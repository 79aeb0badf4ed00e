// SPDX-License-Identifier: GPL-3.0-or-later
// The table of file formats (pointsurf/io/formats.h): the only place their names, extensions
// and magic bytes are written down; the per-format code lives in src/io/<format>.cpp.
#include "pointsurf/io/formats.h"

#include <cstdio>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

using io::detail::lower;
using Path = std::filesystem::path;

bool starts_with(std::string_view s, std::string_view prefix) { return s.substr(0, prefix.size()) == prefix; }

// --- sniffers: true when the first bytes are this format's ---

bool sniff_e57(const FileHead& h) { return starts_with(h.bytes, "ASTM-E57"); }
bool sniff_ply(const FileHead& h) { return starts_with(h.bytes, "ply") && h.bytes.size() > 3 && (h.bytes[3] == '\n' || h.bytes[3] == '\r'); }
// LAS and LAZ share "LASF"; a compressed point format id (bit 7 or 6 of byte 104) is LAZ.
bool las_compressed(const FileHead& h) { return h.bytes.size() > 104 && (static_cast<unsigned char>(h.bytes[104]) & 0xC0) != 0; }
bool sniff_las(const FileHead& h) { return starts_with(h.bytes, "LASF") && !las_compressed(h); }
bool sniff_laz(const FileHead& h) { return starts_with(h.bytes, "LASF") && las_compressed(h); }
// Binary STL: 80-byte header, triangle count, 50 bytes per triangle; recognised by its size
// before the text formats because many exporters start the binary header with "solid".
// Ascii STL: "solid" and a facet.
bool sniff_stl_binary(const FileHead& h) {
  if (h.size >= 84 && h.bytes.size() >= 84) {
    const auto count = io::detail::load_value<std::uint32_t>(h.bytes.data() + 80);
    if (84 + 50 * static_cast<std::uintmax_t>(count) == h.size) return true;
  }
  return false;
}
bool sniff_stl_ascii(const FileHead& h) {
  return starts_with(h.first_line, "solid") && (h.bytes.find("facet") != std::string_view::npos || h.size < 200);
}
bool sniff_pcd(const FileHead& h) {
  return lower(h.bytes.substr(0, 6)) == "# .pcd" || starts_with(h.bytes, "VERSION") || starts_with(h.bytes, "FIELDS");
}
bool sniff_off(const FileHead& h) {
  const std::string_view word = h.first_line.substr(0, h.first_line.find_first_of(" \t"));
  return word.size() >= 3 && word.substr(word.size() - 3) == "OFF" && word.size() <= 6;
}
// OBJ: the first keyword line.
bool sniff_obj(const FileHead& h) {
  const std::string_view& line = h.first_line;
  const std::string_view word = line.substr(0, line.find_first_of(" \t"));
  for (const char* keyword : {"v", "vn", "vt", "f", "o", "g", "mtllib", "usemtl", "s"})
    if (word == keyword) return true;
  return false;
}

// --- writers, adapted to one signature ---

void write_ply(const Path& tmp, const Path&, const PointCloud& c, const std::vector<Triangle>& t, const FieldSet& ff, const WriteOptions& o,
               std::vector<std::string>&) {
  io::detail::write_ply(tmp, c, t, ff, o);
}
void write_xyz(const Path& tmp, const Path& target, const PointCloud& c, const std::vector<Triangle>&, const FieldSet&, const WriteOptions& o,
               std::vector<std::string>&) {
  // The XYZ writer needs to know the family member (csv: header + commas, pts: count line).
  WriteOptions xyz_options = o;
  if (xyz_options.format.empty()) {
    const std::string ext = lower(target.extension().string());
    xyz_options.format = ext == ".csv" ? "csv" : ext == ".pts" ? "pts" : "xyz";
  }
  io::detail::write_xyz(tmp, c, xyz_options);
}
void write_pcd(const Path& tmp, const Path&, const PointCloud& c, const std::vector<Triangle>&, const FieldSet&, const WriteOptions& o,
               std::vector<std::string>& notes) {
  io::detail::write_pcd(tmp, c, o, notes);
}
void note_las_crs(const PointCloud& c, std::vector<std::string>& notes) {
  if (c.crs.wkt.empty() && !c.crs.geokeys.empty())
    notes.push_back("coordinate system written as GeoTIFF keys only: LAS 1.4 point format 6/7 expects WKT, which the input did not give");
}
void write_las(const Path& tmp, const Path&, const PointCloud& c, const std::vector<Triangle>&, const FieldSet&, const WriteOptions& o,
               std::vector<std::string>& notes) {
  io::detail::write_las(tmp, c, o, notes);
  note_las_crs(c, notes);
}
void write_laz(const Path& tmp, const Path&, const PointCloud& c, const std::vector<Triangle>&, const FieldSet&, const WriteOptions& o,
               std::vector<std::string>& notes) {
  io::detail::write_laz(tmp, c, o, notes);
  note_las_crs(c, notes);
}
void write_off(const Path& tmp, const Path&, const PointCloud& c, const std::vector<Triangle>& t, const FieldSet&, const WriteOptions& o,
               std::vector<std::string>&) {
  io::detail::write_off(tmp, c, t, o);
}
void write_obj(const Path& tmp, const Path&, const PointCloud& c, const std::vector<Triangle>& t, const FieldSet&, const WriteOptions& o,
               std::vector<std::string>&) {
  io::detail::write_obj(tmp, c, t, o);
}
void write_stl(const Path& tmp, const Path&, const PointCloud& c, const std::vector<Triangle>& t, const FieldSet&, const WriteOptions& o,
               std::vector<std::string>&) {
  io::detail::write_stl(tmp, c, t, o);
}
void write_e57(const Path& tmp, const Path&, const PointCloud& c, const std::vector<Triangle>&, const FieldSet&, const WriteOptions& o,
               std::vector<std::string>& notes) {
  io::detail::write_e57(tmp, c, o, notes);
}

// Binary or ascii STL (no PCD has a first content line "solid", so asking both before PCD is safe).
bool sniff_stl_any(const FileHead& h) { return sniff_stl_binary(h) || sniff_stl_ascii(h); }

std::vector<FileFormat> make_table() {
  std::vector<FileFormat> t;
  FileFormat f;

  f = {};
  f.name = "ply";
  f.title = "PLY";
  f.extensions = {".ply"};
  f.magic = "`ply` and a line end";
  f.sniff = sniff_ply;
  f.detect_order = 20;
  f.header_required = true;
  f.read = io::detail::read_ply;
  f.write = write_ply;
  f.holds_faces = f.holds_face_fields = true;
  t.push_back(f);

  f = {};
  f.name = "xyz";
  f.title = "XYZ / TXT / PTS / CSV";
  f.extensions = {".xyz", ".txt", ".pts", ".csv", ".xyzn", ".xyzrgb", ".asc"};
  f.aliases = {"txt", "pts", "csv"};
  f.magic = "none: text that no other format claims";
  f.text_fallback = true;
  f.read = io::detail::read_xyz;
  f.write = write_xyz;
  f.extensions_without_field_names = {".pts"};
  t.push_back(f);

  f = {};
  f.name = "pcd";
  f.title = "PCD v0.7";
  f.extensions = {".pcd"};
  f.magic = "`# .PCD`, `VERSION` or `FIELDS`";
  f.sniff = sniff_pcd;
  f.detect_order = 50;
  f.header_required = true;
  f.read = io::detail::read_pcd;
  f.write = write_pcd;
  t.push_back(f);

  f = {};
  f.name = "las";
  f.title = "LAS 1.0-1.4";
  f.extensions = {".las"};
  f.magic = "`LASF`, uncompressed point format";
  f.sniff = sniff_las;
  f.detect_order = 30;
  f.read = io::detail::read_las;
  f.write = write_las;
  t.push_back(f);

  f = {};
  f.name = "laz";
  f.title = "LAZ (LASzip)";
  f.extensions = {".laz"};
  f.magic = "`LASF`, compressed point format (bit 6 or 7 of byte 104)";
  f.sniff = sniff_laz;
  f.detect_order = 30;
  f.read = io::detail::read_laz;
  f.reads_octree_levels = true;
  f.write = write_laz;
  t.push_back(f);

  f = {};
  f.name = "off";
  f.title = "OFF";
  f.extensions = {".off"};
  f.magic = "first word `OFF`, `COFF`, `NOFF`, `CNOFF`, ...";
  f.sniff = sniff_off;
  f.detect_order = 70;
  f.header_required = true;
  f.read = io::detail::read_off;
  f.write = write_off;
  f.holds_faces = true;
  f.holds_fields = false;
  t.push_back(f);

  f = {};
  f.name = "obj";
  f.title = "OBJ";
  f.extensions = {".obj"};
  f.magic = "text whose first line is a keyword: `v`, `vn`, `vt`, `f`, `o`, `g`, `s`, `mtllib`, `usemtl`";
  f.sniff = sniff_obj;
  f.detect_order = 80;
  f.after_binary_check = true;
  f.header_required = true;
  f.read = io::detail::read_obj;
  f.write = write_obj;
  f.holds_faces = true;
  f.holds_fields = false;
  t.push_back(f);

  f = {};
  f.name = "stl";
  f.title = "STL";
  f.extensions = {".stl"};
  f.magic = "binary: size 84 + 50 x the count at byte 80; ascii: `solid` and `facet`";
  f.sniff = sniff_stl_any;
  f.detect_order = 40;
  f.binary_by_extension = true;
  f.header_required = true;
  f.read = io::detail::read_stl;
  f.write = write_stl;
  f.holds_faces = true;
  f.holds_normals = f.holds_colors = f.holds_fields = false;
  t.push_back(f);

  f = {};
  f.name = "e57";
  f.title = "E57 (ASTM E2807)";
  f.extensions = {".e57"};
  f.magic = "`ASTM-E57`";
  f.sniff = sniff_e57;
  f.detect_order = 10;
  f.read = io::detail::read_e57;
  f.write = write_e57;
  t.push_back(f);
  return t;
}

}  // namespace

const std::vector<FileFormat>& file_formats() {
  static const std::vector<FileFormat> table = make_table();
  return table;
}

const FileFormat* find_file_format(std::string_view name) {
  const std::string n = lower(name);
  for (const FileFormat& f : file_formats()) {
    if (f.name == n) return &f;
    for (const std::string& a : f.aliases)
      if (a == n) return &f;
  }
  return nullptr;
}

const FileFormat& file_format(std::string_view name) {
  if (const FileFormat* f = find_file_format(name)) return *f;
  throw UsageError(fmt::format("unknown format '{}': expected {}", name, known_format_names(", ")));
}

const FileFormat* find_format_for_extension(const std::filesystem::path& path) {
  const std::string ext = lower(path.extension().string());
  for (const FileFormat& f : file_formats())
    for (const std::string& e : f.extensions)
      if (e == ext) return &f;
  return nullptr;
}

const FileFormat& format_for_extension(const std::filesystem::path& path) {
  if (const FileFormat* f = find_format_for_extension(path)) return *f;
  const std::string ext = lower(path.extension().string());
  throw UsageError(fmt::format("{}: unknown output format '{}': expected {}", io::detail::display_name(path),
                               ext.empty() ? std::string("(no extension)") : ext, known_extensions(", ")));
}

bool format_holds_faces(std::string_view name) {
  const FileFormat* f = find_file_format(name);
  return f != nullptr && f->holds_faces;
}

std::string known_format_names(std::string_view separator) {
  std::string out;
  for (const FileFormat& f : file_formats()) out += (out.empty() ? "" : std::string(separator)) + f.name;
  return out;
}

std::string known_extensions(std::string_view separator) {
  std::string out;
  for (const FileFormat& f : file_formats())
    for (const std::string& e : f.extensions) out += (out.empty() ? "" : std::string(separator)) + e;
  return out;
}

std::vector<std::string> format_names() {
  std::vector<std::string> out;
  for (const FileFormat& f : file_formats()) out.push_back(f.name);
  return out;
}

std::string format_table_markdown() {
  auto yes = [](bool b) { return b ? "yes" : "no"; };
  std::string out =
      "| name | format | extensions | recognised by | read | write | faces | face fields | normals | colours | fields |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const FileFormat& f : file_formats()) {
    std::string ext;
    for (const std::string& e : f.extensions) ext += (ext.empty() ? "`" : " `") + e + "`";
    std::string fields = yes(f.holds_fields);
    for (const std::string& e : f.extensions_without_field_names) fields += fmt::format(" (`{}`: unnamed columns)", e);
    out += fmt::format("| `{}` | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", f.name, f.title, ext, f.magic, yes(f.read != nullptr),
                       yes(f.write != nullptr), yes(f.holds_faces), yes(f.holds_face_fields), yes(f.holds_normals), yes(f.holds_colors), fields);
  }
  return out;
}

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  io::detail::TemporaryOutput out(path);
  {
    std::FILE* f = std::fopen(out.path().c_str(), "wb");
    if (!f) throw Error(fmt::format("{}: cannot write: cannot open a temporary file in its directory", io::detail::display_name(path)));
    const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    const bool closed = std::fclose(f) == 0;
    if (!ok || !closed) throw Error(fmt::format("{}: cannot write (disk full?)", io::detail::display_name(path)));
  }
  out.commit();
}

}  // namespace pointsurf
