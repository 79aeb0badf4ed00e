// SPDX-License-Identifier: GPL-3.0-or-later
// The format table: every format round-trips through its writer and reader by name and by
// extension, content sniffing picks each format, unknown names and extensions list the known
// ones, docs/formats.md holds the table, and atomic file writing leaves whole files or none.
#include "pointsurf/io/formats.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::error_of;

// A tetrahedron: a mesh every format can hold (mesh formats its faces, the others its vertices).
TriangleMesh tetrahedron() {
  PointCloud c;
  c.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0, 0, 1)};
  return TriangleMesh{std::move(c), {Triangle(0, 2, 1), Triangle(0, 1, 3), Triangle(0, 3, 2), Triangle(1, 2, 3)}, {}};
}

// The file names in `dir`, sorted.
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The points read back from `path` match the tetrahedron (in order, to the formats' precision),
// and a format that holds faces gives its four faces back.
void expect_tetrahedron(const fs::path& path, const FileFormat& f, const ReadOptions& options = {}) {
  SCOPED_TRACE(path.string());
  const CloudReadResult r = read_point_cloud(path, options);
  EXPECT_EQ(r.format, f.name);
  const TriangleMesh m = tetrahedron();
  ASSERT_EQ(r.cloud.size(), m.vertices.positions.size());
  // STL stores each facet's corners and the reader welds them, in its own order: compare as sets.
  for (std::size_t i = 0; i < m.vertices.positions.size(); ++i) {
    double nearest = (r.cloud.positions[i] - m.vertices.positions[i]).norm();
    if (f.name == "stl")
      for (const Vector3d& v : m.vertices.positions) nearest = std::min(nearest, (r.cloud.positions[i] - v).norm());
    EXPECT_LT(nearest, 1e-4) << "point " << i;
  }
  if (f.holds_faces) {
    const MeshReadResult mr = read_mesh(path, options);
    EXPECT_EQ(mr.mesh.triangles.size(), 4u);
  }
}

TEST(FileFormats, NamesAliasesAndExtensionsAreUnique) {
  std::set<std::string> names, extensions;
  for (const FileFormat& f : file_formats()) {
    EXPECT_TRUE(names.insert(f.name).second) << f.name;
    for (const std::string& a : f.aliases) EXPECT_TRUE(names.insert(a).second) << a;
    ASSERT_FALSE(f.extensions.empty()) << f.name;
    for (const std::string& e : f.extensions) {
      EXPECT_TRUE(extensions.insert(e).second) << e;
      EXPECT_EQ(e.front(), '.');
    }
    EXPECT_NE(f.read, nullptr) << f.name;
  }
  EXPECT_EQ(format_names().front(), file_formats().front().name);
}

TEST(FileFormats, EveryFormatRoundTripsByName) {
  const fs::path dir = test::temp_dir("formats_by_name");
  for (const FileFormat& f : file_formats()) {
    if (f.write == nullptr) continue;
    // A neutral extension: the name alone chooses writer and reader.
    const fs::path path = dir / (f.name + "_by_name.dat");
    WriteOptions w;
    w.format = f.name;
    write_mesh(path, tetrahedron(), w);
    ReadOptions r;
    r.format = f.name;
    expect_tetrahedron(path, f, r);
  }
}

TEST(FileFormats, EveryFormatRoundTripsByEveryExtension) {
  const fs::path dir = test::temp_dir("formats_by_extension");
  for (const FileFormat& f : file_formats()) {
    if (f.write == nullptr) continue;
    for (const std::string& ext : f.extensions) {
      const fs::path path = dir / ("tetra" + ext);
      EXPECT_EQ(&format_for_extension(path), &f);
      EXPECT_EQ(format_from_extension(path), f.name);
      write_mesh(path, tetrahedron());
      EXPECT_EQ(detect_format(path), f.name) << path;
      expect_tetrahedron(path, f);
    }
  }
  // Nothing but the outputs: no temporary file left.
  for (const std::string& name : entries(dir)) EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
}

TEST(FileFormats, SniffingPicksEachFormatWhateverTheExtension) {
  const fs::path dir = test::temp_dir("formats_sniff");
  for (const FileFormat& f : file_formats()) {
    if (f.write == nullptr) continue;
    const fs::path path = dir / (f.name + "_content.bin");
    WriteOptions w;
    w.format = f.name;
    write_mesh(path, tetrahedron(), w);
    EXPECT_EQ(detect_format(path), f.name) << "written as " << f.name;
    EXPECT_EQ(read_point_cloud(path).format, f.name);
  }
}

TEST(FileFormats, AliasesNameTheirFormat) {
  for (const FileFormat& f : file_formats()) {
    EXPECT_EQ(&file_format(f.name), &f);
    for (const std::string& a : f.aliases) EXPECT_EQ(find_file_format(a), &f) << a;
  }
  EXPECT_EQ(find_file_format("PLY"), find_file_format("ply"));
  EXPECT_EQ(find_file_format("nope"), nullptr);
}

TEST(FileFormats, UnknownExtensionOrNameListsTheKnownOnes) {
  const std::string ext_error = error_of<UsageError>([] { format_for_extension("scan.foo"); });
  EXPECT_TRUE(contains(ext_error, "scan.foo")) << ext_error;
  EXPECT_TRUE(contains(ext_error, "'.foo'")) << ext_error;
  const std::string name_error = error_of<UsageError>([] { file_format("foo"); });
  for (const FileFormat& f : file_formats()) {
    for (const std::string& e : f.extensions) EXPECT_TRUE(contains(ext_error, e)) << e << " missing from: " << ext_error;
    EXPECT_TRUE(contains(name_error, f.name)) << f.name << " missing from: " << name_error;
  }
  EXPECT_THROW(format_for_extension("scan"), UsageError);
  EXPECT_THROW(check_output_path(test::temp_dir("formats_unknown") / "out.foo"), UsageError);
  // A write with an unknown --format names the known formats too.
  WriteOptions w;
  w.format = "foo";
  const std::string write_error = error_of<UsageError>([&] { write_mesh(test::temp_dir("formats_unknown") / "out.ply", tetrahedron(), w); });
  for (const FileFormat& f : file_formats()) EXPECT_TRUE(contains(write_error, f.name)) << write_error;
}

TEST(FileFormats, DocsHoldTheTable) {
  const std::string doc = test::read_bytes(test::data_path("../docs/formats.md"));
  const std::string begin = "<!-- format-table -->\n", end = "<!-- /format-table -->";
  const std::size_t a = doc.find(begin), b = doc.find(end);
  ASSERT_NE(a, std::string::npos) << "docs/formats.md: no " << begin;
  ASSERT_NE(b, std::string::npos) << "docs/formats.md: no " << end;
  if (doc.substr(a + begin.size(), b - a - begin.size()) != format_table_markdown()) {
    const fs::path fresh = fs::temp_directory_path() / "pointsurf_format_table.md";
    test::write_bytes(fresh, format_table_markdown());
    ADD_FAILURE() << "docs/formats.md is out of date: put " << fresh.string() << " (format_table_markdown()) between the markers";
  }
}

// --- atomic file writing (render's PNG, reports) ---

const std::string kPngHeader = std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16);

TEST(WriteFileAtomically, WritesTheBytesAndLeavesNoTemporaryFile) {
  const fs::path dir = test::temp_dir("atomic_png");
  const fs::path path = dir / "picture.png";
  const std::string bytes = kPngHeader + std::string(100, 'x');
  write_file_atomically(path, bytes);
  EXPECT_EQ(test::read_bytes(path), bytes);
  EXPECT_EQ(test::read_bytes(path).substr(0, 8), kPngHeader.substr(0, 8));
  EXPECT_EQ(entries(dir), std::vector<std::string>{"picture.png"});
  // Replacing keeps one file with the new content.
  write_file_atomically(path, "second");
  EXPECT_EQ(test::read_bytes(path), "second");
  EXPECT_EQ(entries(dir), std::vector<std::string>{"picture.png"});
}

TEST(WriteFileAtomically, AFailedWriteLeavesNoHalfFile) {
  const fs::path dir = test::temp_dir("atomic_png_fail");
  // The target is a directory: the bytes go to a temporary file whose rename fails.
  const fs::path target = dir / "taken.png";
  fs::create_directories(target);
  const std::string e = error_of<Error>([&] { write_file_atomically(target, kPngHeader); });
  EXPECT_TRUE(contains(e, "taken.png")) << e;
  EXPECT_EQ(entries(dir), std::vector<std::string>{"taken.png"});
  EXPECT_TRUE(fs::is_directory(target));
  EXPECT_TRUE(fs::is_empty(target));
  // A missing directory: an error naming the file, nothing created.
  const std::string missing = error_of<Error>([&] { write_file_atomically(dir / "nowhere" / "p.png", kPngHeader); });
  EXPECT_TRUE(contains(missing, "p.png")) << missing;
  EXPECT_FALSE(fs::exists(dir / "nowhere"));
}

}  // namespace
}  // namespace pointsurf
