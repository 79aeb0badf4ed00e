// SPDX-License-Identifier: GPL-3.0-or-later
// Format detection, dispatch to the per-format readers and writers, and the post-processing
// every reader shares: non-finite points, polygon triangulation, atomic output files.
#include "pointsurf/io/io.h"
#include "pointsurf/io/formats.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <limits>
#include <random>
#include <unistd.h>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

using io::detail::display_name;
using io::detail::lower;
using io::detail::TemporaryOutput;

std::string read_head(const std::filesystem::path& path, std::size_t bytes, std::uintmax_t& file_size) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(fmt::format("{}: no such file", display_name(path)));
  if (std::filesystem::is_directory(path, ec)) throw InputError(fmt::format("{}: is a directory, expected a file", display_name(path)));
  file_size = std::filesystem::file_size(path, ec);
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(fmt::format("{}: cannot open for reading", display_name(path)));
  std::string head(bytes, '\0');
  head.resize(std::fread(head.data(), 1, bytes, f));
  std::fclose(f);
  return head;
}

// First non-blank, non-comment line of `head`.
std::string_view first_content_line(std::string_view head, char comment) {
  io::detail::TextCursor cursor(head);
  std::string_view line;
  while (cursor.next_line(line)) {
    std::size_t i = line.find_first_not_of(" \t");
    if (i == std::string_view::npos) continue;
    line.remove_prefix(i);
    if (line.front() == comment) continue;
    return line;
  }
  return {};
}

bool looks_binary(std::string_view head) {
  std::size_t bad = 0;
  for (unsigned char c : head)
    if (c == 0 || (c < 32 && c != '\n' && c != '\r' && c != '\t' && c != '\v' && c != '\f')) ++bad;
  return bad > 0;
}

}  // namespace

void check_output_path(const std::filesystem::path& path, bool no_clobber, const std::string& format) {
  if (format.empty()) format_from_extension(path);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw UsageError(fmt::format("{}: is a directory, not an output file", path.string()));
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  if (!std::filesystem::is_directory(dir, ec))
    throw UsageError(fmt::format("{}: cannot write: directory {} does not exist", path.string(), dir.string()));
  if (::access(dir.c_str(), W_OK) != 0)
    throw UsageError(fmt::format("{}: cannot write: directory {} is not writable", path.string(), dir.string()));
  if (std::filesystem::exists(path, ec)) {
    if (no_clobber) throw UsageError(fmt::format("{}: exists (--no-clobber)", path.string()));
    if (::access(path.c_str(), W_OK) != 0) throw UsageError(fmt::format("{}: exists and is not writable", path.string()));
  }
  // A writer makes its temporary file beside the output and renames it into place: make one now
  // (removed at once), so that a directory where no file can be made (a read-only mount, /proc,
  // a full disk's quota) is refused before any work, whatever access() says for root.
  const TemporaryOutput probe(path);
  const int fd = ::open(probe.path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw UsageError(fmt::format("{}: cannot write in directory {}: {}", path.string(), dir.string(), std::strerror(errno)));
  ::close(fd);
}

void remove_output(const std::filesystem::path& path) noexcept {
  std::error_code ec;
  std::filesystem::remove(path, ec);
}

bool same_path(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code ec;
  const std::filesystem::path ca = std::filesystem::weakly_canonical(a, ec);
  const std::filesystem::path cb = std::filesystem::weakly_canonical(b, ec);
  return ca == cb;
}

void check_input_path(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(fmt::format("{}: no such file", path.string()));
  if (std::filesystem::is_directory(path, ec)) throw InputError(fmt::format("{}: is a directory, not a file", path.string()));
  if (::access(path.c_str(), R_OK) != 0) throw InputError(fmt::format("{}: cannot read (permission denied)", path.string()));
}

std::string format_from_extension(const std::filesystem::path& path) { return format_for_extension(path).name; }

std::string detect_format(const std::filesystem::path& path) {
  std::uintmax_t size = 0;
  const std::string head = read_head(path, 4096, size);
  if (size == 0 || head.empty()) throw InputError(fmt::format("{}: file is empty", display_name(path)));
  const FileHead h{head, size, first_content_line(head, '#')};
  // The sniffers in their order (formats.cpp): magic bytes first, then text headers.
  std::vector<const FileFormat*> order;
  for (const FileFormat& f : file_formats())
    if (f.sniff) order.push_back(&f);
  std::stable_sort(order.begin(), order.end(), [](const FileFormat* a, const FileFormat* b) { return a->detect_order < b->detect_order; });
  for (const FileFormat* f : order)
    if (!f->after_binary_check && f->sniff(h)) return f->name;
  const FileFormat* by_extension = find_format_for_extension(path);
  if (looks_binary(head)) {
    // E.g. a binary .stl whose size disagrees with its count: its reader says where it ends.
    if (by_extension && by_extension->binary_by_extension) return by_extension->name;
    std::string names;
    for (const FileFormat* f : order)
      if (!f->after_binary_check) names += (names.empty() ? "" : ", ") + f->title;
    throw InputError(fmt::format("{}: unknown format: binary content that is none of {}", display_name(path), names));
  }
  for (const FileFormat* f : order)
    if (f->after_binary_check && f->sniff(h)) return f->name;
  if (by_extension && by_extension->header_required)
    throw InputError(fmt::format("{}: not a valid {} file: the header is missing", display_name(path), lower(path.extension().string()).substr(1)));
  for (const FileFormat& f : file_formats())
    if (f.text_fallback) return f.name;
  throw InputError(fmt::format("{}: unknown format: text that is none of {}", display_name(path), known_format_names()));
}

namespace {

io::detail::RawData read_raw(const std::filesystem::path& path, const ReadOptions& options, std::string& format) {
  const std::string name = options.format.empty() ? detect_format(path) : lower(options.format);
  const FileFormat* f = find_file_format(name);
  if (f == nullptr || f->read == nullptr)
    throw UsageError(fmt::format("{}: unknown format '{}': expected {}", display_name(path), name, known_format_names(", ")));
  format = f->name;
  return f->read(path, options);
}

bool finite(const Vector3d& p) { return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()); }

// Drops points with NaN/Inf coordinates; returns old index -> new index (-1 dropped) when
// `want_remap` (meshes, whose faces need it), or an empty vector when nothing was dropped.
std::vector<int> drop_nonfinite(PointCloud& cloud, const std::filesystem::path& path, bool strict, std::size_t& dropped,
                                bool want_remap) {
  std::size_t first_bad = cloud.size();
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (!finite(cloud.positions[i])) { first_bad = i; break; }
  if (first_bad == cloud.size()) return {};
  if (strict)
    throw InputError(fmt::format("{}: point {}: non-finite coordinate ({}, {}, {}); without --strict such points are dropped and counted",
                                 display_name(path), first_bad, cloud.positions[first_bad].x(), cloud.positions[first_bad].y(),
                                 cloud.positions[first_bad].z()));
  std::vector<int> remap(want_remap ? cloud.size() : 0, -1);
  std::vector<std::size_t> keep;
  keep.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!finite(cloud.positions[i])) continue;
    if (want_remap) remap[i] = static_cast<int>(keep.size());
    keep.push_back(i);
  }
  dropped += cloud.size() - keep.size();
  cloud = cloud.select(keep);
  return remap;
}

}  // namespace

namespace {

// The points inside the box min..max (xmin, ymin, zmin, xmax, ymax, zmax), with their attributes.
void keep_inside(PointCloud& cloud, const std::array<double, 6>& box) {
  std::vector<std::size_t> inside;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vector3d& p = cloud.positions[i];
    if (p.x() >= box[0] && p.y() >= box[1] && p.z() >= box[2] && p.x() <= box[3] && p.y() <= box[4] && p.z() <= box[5]) inside.push_back(i);
  }
  if (inside.size() != cloud.size()) cloud = cloud.select(inside);
}

}  // namespace

CloudReadResult read_point_cloud(const std::filesystem::path& path, const ReadOptions& options) {
  CloudReadResult result;
  io::detail::RawData raw = read_raw(path, options, result.format);
  result.encoding = raw.encoding;
  result.warnings = std::move(raw.warnings);
  result.face_count = raw.polygons.size() + raw.triangles.size();
  result.dropped_nonfinite = raw.dropped_nonfinite;
  result.scans = std::move(raw.scans);
  if (options.strict && raw.dropped_nonfinite > 0)
    throw InputError(fmt::format("{}: {} points with NaN coordinates (organized cloud); without --strict they are dropped and counted",
                                 display_name(path), raw.dropped_nonfinite));
  drop_nonfinite(raw.cloud, path, options.strict, result.dropped_nonfinite, false);
  if (options.copc_level >= 0 && !file_format(result.format).reads_octree_levels)
    throw UsageError(fmt::format("{}: an octree level is a COPC (LAZ) option; this file is {}", display_name(path), result.format));
  if (options.bounds) keep_inside(raw.cloud, *options.bounds);
  raw.cloud.validate();
  result.cloud = std::move(raw.cloud);
  return result;
}

MeshReadResult read_mesh(const std::filesystem::path& path, const ReadOptions& options) {
  MeshReadResult result;
  io::detail::RawData raw = read_raw(path, options, result.format);
  result.encoding = raw.encoding;
  result.warnings = std::move(raw.warnings);
  result.dropped_nonfinite = raw.dropped_nonfinite;
  // Triangles index vertices with int (as every mesh format in the field does).
  if (raw.cloud.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw InputError(fmt::format("{}: {} vertices: meshes of more than {} vertices are not supported", display_name(path),
                                 raw.cloud.size(), std::numeric_limits<int>::max()));
  const std::vector<int> remap = drop_nonfinite(raw.cloud, path, options.strict, result.dropped_nonfinite, true);
  const int n = static_cast<int>(raw.cloud.size());
  std::vector<Triangle> triangles;
  triangles.reserve(raw.triangles.size() + raw.polygons.size());
  // Face fields follow the triangles: a polygon's value goes to each triangle of its fan, a
  // dropped face takes its value with it.
  std::vector<std::size_t> source_face;
  const bool face_fields = !raw.face_fields.empty();
  if (face_fields) source_face.reserve(raw.triangles.size() + raw.polygons.size());
  auto add = [&](int a, int b, int c, std::size_t face) {
    if (!remap.empty()) { a = remap[a]; b = remap[b]; c = remap[c]; }
    if (a < 0 || b < 0 || c < 0 || a == b || b == c || a == c) { ++result.dropped_faces; return; }
    triangles.emplace_back(a, b, c);
    if (face_fields) source_face.push_back(face);
  };
  const int n_in = static_cast<int>(remap.empty() ? n : remap.size());
  auto check = [&](int idx, std::size_t face) {
    if (idx < 0 || idx >= n_in)
      throw InputError(fmt::format("{}: face {}: vertex index {} out of range [0, {})", display_name(path), face, idx, n_in));
  };
  for (std::size_t f = 0; f < raw.triangles.size(); ++f) {
    const Triangle& t = raw.triangles[f];
    check(t[0], f); check(t[1], f); check(t[2], f);
    add(t[0], t[1], t[2], f);
  }
  for (std::size_t f = 0; f < raw.polygons.size(); ++f) {
    const std::vector<int>& poly = raw.polygons[f];
    for (int idx : poly) check(idx, raw.triangles.size() + f);
    if (poly.size() < 3) { ++result.dropped_faces; continue; }
    if (poly.size() > 3) ++result.polygons_triangulated;
    for (std::size_t k = 1; k + 1 < poly.size(); ++k) add(poly[0], poly[k], poly[k + 1], raw.triangles.size() + f);
  }
  raw.cloud.validate();
  FieldSet fields;
  for (const ScalarField& in : raw.face_fields) {
    ScalarField& out = fields.add(in.name, source_face.size(), in.type);
    for (std::size_t t = 0; t < source_face.size(); ++t) out.values[t] = in.values[source_face[t]];
  }
  result.mesh = TriangleMesh{std::move(raw.cloud), std::move(triangles), std::move(fields)};
  return result;
}

namespace {


WriteResult write_any(const std::filesystem::path& path, const PointCloud& cloud, const std::vector<Triangle>& triangles,
                      const FieldSet& face_fields, const WriteOptions& options) {
  WriteResult result;
  cloud.validate();
  const FileFormat* f = options.format.empty() ? &format_for_extension(path) : find_file_format(options.format);
  if (f == nullptr || f->write == nullptr)
    throw UsageError(fmt::format("{}: unknown format '{}': expected {}", display_name(path), options.format, known_format_names(", ")));
  TemporaryOutput out(path);
  f->write(out.path(), path, cloud, triangles, face_fields, options, result.notes);
  out.commit();
  return result;
}

}  // namespace

WriteResult write_point_cloud(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options) {
  return write_any(path, cloud, {}, {}, options);
}

WriteResult write_mesh(const std::filesystem::path& path, const TriangleMesh& mesh, const WriteOptions& options) {
  mesh.validate();
  // The vertex attributes travel as a cloud; this copies the vertices once, which is small
  // next to the file I/O.
  return write_any(path, mesh.vertices, mesh.triangles, mesh.face_fields, options);
}

}  // namespace pointsurf
