// SPDX-License-Identifier: GPL-3.0-or-later
// The format dispatch: detection from content, non-finite points, face remapping, and
// atomic writes.
#include "pointsurf/io/io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::write_bytes;
using test::error_of;
using test::contains;

namespace fs = std::filesystem;

// Names of the entries of `dir`, sorted.
std::vector<std::string> list_dir(const fs::path& dir) {
  std::vector<std::string> names;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// A LAS 1.2 public header block (227 bytes) with no points; `point_format` byte at offset 104.
std::string las_header(std::uint8_t point_format) {
  std::string bytes(227, '\0');
  std::memcpy(bytes.data(), "LASF", 4);
  bytes[24] = 1;
  bytes[25] = 2;
  bytes[94] = static_cast<char>(227);
  bytes[96] = static_cast<char>(227);
  bytes[104] = static_cast<char>(point_format);
  bytes[105] = 20;
  return bytes;
}

TEST(DetectFormat, RecognisesEachFormatFromItsContent) {
  const fs::path dir = test::temp_dir("detect_format");
  struct Case {
    std::string name;
    std::string bytes;
    std::string format;
  };
  std::string binary_stl(80, ' ');
  std::memcpy(binary_stl.data(), "solid but binary", 16);  // as many exporters write it
  const std::uint32_t one = 1;
  binary_stl.append(reinterpret_cast<const char*>(&one), 4);
  binary_stl.append(50, '\0');
  const std::vector<Case> cases{
      {"a.dat", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nend_header\n", "ply"},
      {"b.dat", "ply\r\nformat ascii 1.0\r\n", "ply"},
      {"c.dat", "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\n", "pcd"},
      {"d.dat", "VERSION 0.7\nFIELDS x y z\n", "pcd"},
      {"e.dat", las_header(0), "las"},
      {"f.dat", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "off"},
      {"g.dat", "# comment first\nCOFF\n", "off"},
      {"h.dat", "solid cube\n  facet normal 0 0 1\n    outer loop\n", "stl"},
      {"i.dat", binary_stl, "stl"},
      {"j.dat", "# made by hand\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "obj"},
      {"k.dat", "mtllib x.mtl\nv 0 0 0\n", "obj"},
      {"l.xyz", "1 2 3\n4 5 6\n", "xyz"},
      {"m.txt", "1.5,2.5,3.5\n", "xyz"},
      {"n.dat", "0.1 0.2 0.3 0 0 1\n", "xyz"},
  };
  for (const Case& c : cases) {
    write_bytes(dir / c.name, c.bytes);
    EXPECT_EQ(detect_format(dir / c.name), c.format) << c.name;
  }
}

TEST(DetectFormat, BinaryStlIsRecognisedByItsSize) {
  const fs::path dir = test::temp_dir("detect_stl_size");
  std::string bytes(80, '\0');
  const std::uint32_t count = 3;
  bytes.append(reinterpret_cast<const char*>(&count), 4);
  bytes.append(3 * 50, '\x01');
  write_bytes(dir / "part.bin", bytes);
  EXPECT_EQ(detect_format(dir / "part.bin"), "stl");
  bytes.push_back('\0');  // one byte too many: no longer a binary STL by size...
  write_bytes(dir / "part.bin", bytes);
  EXPECT_TRUE(contains(error_of<InputError>([&] { detect_format(dir / "part.bin"); }), "unknown format"));
  // ...but named .stl it goes to the STL reader, which tolerates trailing padding (and words
  // a truncation: see Io.TruncatedBinaryStlSaysWhereItEnds).
  write_bytes(dir / "part.stl", bytes);
  EXPECT_EQ(detect_format(dir / "part.stl"), "stl");
  EXPECT_NO_THROW(read_mesh(dir / "part.stl"));
}

TEST(DetectFormat, EmptyAndMissingFiles) {
  const fs::path dir = test::temp_dir("detect_empty");
  write_bytes(dir / "empty.ply", "");
  EXPECT_TRUE(contains(error_of<InputError>([&] { detect_format(dir / "empty.ply"); }), "empty.ply: file is empty"));
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "empty.ply"); }), "empty.ply: file is empty"));
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "missing.ply"); }), "missing.ply: no such file"));
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_mesh(dir); }), "is a directory, expected a file"));
}

TEST(DetectFormat, HeaderlessTextWithAMeshExtensionIsAnError) {
  const fs::path dir = test::temp_dir("detect_no_header");
  write_bytes(dir / "numbers.ply", "1 2 3\n");
  EXPECT_TRUE(contains(error_of<InputError>([&] { detect_format(dir / "numbers.ply"); }), "numbers.ply: not a valid ply file"));
}

TEST(DetectFormat, LazIsDetectedByContent) {
  const fs::path dir = test::temp_dir("detect_laz");
  // Uncompressed points in a file named .laz are LAS.
  write_bytes(dir / "tile.laz", las_header(0));
  EXPECT_EQ(detect_format(dir / "tile.laz"), "las");
  // A compressed point format (bit 7 set) inside a file named .las is LAZ (this header, too
  // short for format 3, is refused).
  write_bytes(dir / "tile.las", las_header(0x80 | 3));
  EXPECT_EQ(detect_format(dir / "tile.las"), "laz");
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "tile.las"); }), "tile.las: point record length 20 is shorter"));
  EXPECT_EQ(format_from_extension(dir / "out.laz"), "laz");
}

TEST(DetectFormat, ExtensionNamesTheOutputFormat) {
  EXPECT_EQ(format_from_extension("a.PLY"), "ply");
  EXPECT_EQ(format_from_extension("a.pts"), "xyz");
  EXPECT_EQ(format_from_extension("a.csv"), "xyz");
  EXPECT_EQ(format_from_extension("dir.v2/a.las"), "las");
  EXPECT_TRUE(contains(error_of<UsageError>([] { format_from_extension("a.docx"); }), "unknown output format '.docx'"));
  EXPECT_TRUE(contains(error_of<UsageError>([] { format_from_extension("noext"); }), "(no extension)"));
}

// Four points, the first with a NaN coordinate, and two faces: one uses the NaN point.
const char* const kNanMesh =
    "ply\nformat ascii 1.0\nelement vertex 4\n"
    "property double x\nproperty double y\nproperty double z\nproperty uchar label\n"
    "element face 3\nproperty list uchar int vertex_indices\nend_header\n"
    "nan 0 0 10\n1 0 0 11\n0 1 0 12\n0 0 inf 13\n"
    "3 1 2 0\n3 1 2 3\n4 0 1 2 3\n";

TEST(ReadPointCloud, DropsAndCountsNonFinitePoints) {
  const fs::path path = test::temp_dir("read_nan") / "nan.ply";
  write_bytes(path, kNanMesh);
  const CloudReadResult result = read_point_cloud(path);
  EXPECT_EQ(result.dropped_nonfinite, 2u);
  EXPECT_EQ(result.face_count, 3u);
  ASSERT_EQ(result.cloud.size(), 2u);
  EXPECT_EQ(result.cloud.positions[0], Vector3d(1, 0, 0));
  EXPECT_EQ(result.cloud.positions[1], Vector3d(0, 1, 0));
  EXPECT_EQ(result.cloud.fields.find("label")->values, (std::vector<double>{11, 12}));
}

TEST(ReadPointCloud, StrictRefusesNonFinitePoints) {
  const fs::path path = test::temp_dir("read_nan_strict") / "nan.ply";
  write_bytes(path, kNanMesh);
  ReadOptions options;
  options.strict = true;
  const std::string message = error_of<InputError>([&] { read_point_cloud(path, options); });
  EXPECT_TRUE(contains(message, "nan.ply: point 0: non-finite coordinate")) << message;
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_mesh(path, options); }), "nan.ply: point 0: non-finite coordinate"));
}

TEST(ReadMesh, DropsFacesOfDroppedVerticesAndRemapsTheRest) {
  const fs::path path = test::temp_dir("read_mesh_nan") / "nan.ply";
  std::string text = kNanMesh;
  text.replace(text.find("0 0 inf"), 7, "0 0 1");  // only vertex 0 is non-finite
  write_bytes(path, text);
  const MeshReadResult result = read_mesh(path);
  EXPECT_EQ(result.dropped_nonfinite, 1u);
  ASSERT_EQ(result.mesh.vertex_count(), 3u);
  EXPECT_EQ(result.mesh.vertices.positions[2], Vector3d(0, 0, 1));
  EXPECT_EQ(result.mesh.vertices.fields.find("label")->values, (std::vector<double>{11, 12, 13}));
  // Face (1 2 0) uses vertex 0 and goes; face (1 2 3) becomes (0 1 2); the quad (0 1 2 3)
  // fans into (0 1 2), which uses vertex 0, and (0 2 3), which does too.
  EXPECT_EQ(result.mesh.triangles, (std::vector<Triangle>{Triangle(0, 1, 2)}));
  EXPECT_EQ(result.dropped_faces, 3u);
  EXPECT_EQ(result.polygons_triangulated, 1u);
}

TEST(ReadPointCloud, ForcedFormatOverridesDetection) {
  const fs::path path = test::temp_dir("read_forced") / "cloud.dat";
  write_bytes(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n");
  ReadOptions options;
  options.format = "PLY";
  EXPECT_EQ(read_point_cloud(path, options).cloud.positions.at(0), Vector3d(1, 2, 3));
  options.format = "vrml";
  EXPECT_TRUE(contains(error_of<UsageError>([&] { read_point_cloud(path, options); }), "unknown format 'vrml'"));
}

TEST(Write, MissingDirectoryIsAnErrorAndLeavesNothing) {
  const fs::path dir = test::temp_dir("write_missing_dir");
  const fs::path target = dir / "not_here" / "cloud.ply";
  const std::string message = error_of<Error>([&] { write_point_cloud(target, test::sample_plane(10)); });
  EXPECT_TRUE(contains(message, "does not exist")) << message;
  EXPECT_FALSE(fs::exists(dir / "not_here"));
  EXPECT_TRUE(list_dir(dir).empty());
}

TEST(Write, SuccessLeavesOnlyTheTarget) {
  const fs::path dir = test::temp_dir("write_atomic_ok");
  const PointCloud cloud = test::sample_sphere(200);
  write_point_cloud(dir / "sphere.ply", cloud);
  EXPECT_EQ(list_dir(dir), (std::vector<std::string>{"sphere.ply"}));
  // Overwriting an existing file also leaves nothing else behind.
  write_point_cloud(dir / "sphere.ply", test::sample_sphere(20));
  EXPECT_EQ(list_dir(dir), (std::vector<std::string>{"sphere.ply"}));
  EXPECT_EQ(read_point_cloud(dir / "sphere.ply").cloud.size(), 20u);
}

TEST(Write, FailingWriterLeavesNeitherTargetNorTemporary) {
  const fs::path dir = test::temp_dir("write_atomic_fail");
  PointCloud cloud = test::sample_plane(100, 10.0);
  for (Vector3d& p : cloud.positions) p.x() += 6500000.0;
  WriteOptions options;
  options.single_precision = true;
  EXPECT_THROW(write_point_cloud(dir / "geo.ply", cloud, options), UsageError);
  EXPECT_TRUE(list_dir(dir).empty());

  // An existing target stays as it was when the new write fails.
  write_point_cloud(dir / "geo.ply", test::sample_plane(5));
  EXPECT_THROW(write_point_cloud(dir / "geo.ply", cloud, options), UsageError);
  EXPECT_EQ(list_dir(dir), (std::vector<std::string>{"geo.ply"}));
  EXPECT_EQ(read_point_cloud(dir / "geo.ply").cloud.size(), 5u);
}

TEST(Write, UnknownExtensionIsAUsageError) {
  const fs::path dir = test::temp_dir("write_unknown_ext");
  const std::string message = error_of<UsageError>([&] { write_point_cloud(dir / "cloud.vrml", test::sample_plane(3)); });
  EXPECT_TRUE(contains(message, "unknown output format '.vrml'")) << message;
  WriteOptions options;
  options.format = "ply";
  write_point_cloud(dir / "cloud.vrml", test::sample_plane(3), options);  // a forced format needs no extension
  EXPECT_EQ(detect_format(dir / "cloud.vrml"), "ply");
  options.format = "vrml";
  EXPECT_TRUE(contains(error_of<UsageError>([&] { write_point_cloud(dir / "x.ply", test::sample_plane(3), options); }), "unknown format 'vrml'"));
  EXPECT_EQ(list_dir(dir), (std::vector<std::string>{"cloud.vrml"}));
}

TEST(Write, MismatchedAttributeSizesAreRefused) {
  const fs::path dir = test::temp_dir("write_invalid");
  PointCloud cloud = test::sample_plane(4);
  cloud.colors.resize(3);
  EXPECT_TRUE(contains(error_of<InputError>([&] { write_point_cloud(dir / "c.ply", cloud); }), "3 colours for 4 points"));
  EXPECT_TRUE(list_dir(dir).empty());
}

// Writers work on a temporary file; their messages must name the file the user asked for.
TEST(Io, WriterErrorsNameTheTargetNotTheTemporaryFile) {
  const std::filesystem::path dir = test::temp_dir("writer_error_name");
  PointCloud cloud = test::sample_sphere(10);
  try {
    write_point_cloud(dir / "cloud.stl", cloud);
    FAIL() << "expected UsageError";
  } catch (const UsageError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("cloud.stl"), std::string::npos) << msg;
    EXPECT_EQ(msg.find(".tmp-"), std::string::npos) << msg;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
  std::filesystem::remove_all(dir);
}

// A truncated binary STL is reported by the STL reader with the facet where the file ends.
TEST(Io, TruncatedBinaryStlSaysWhereItEnds) {
  const std::filesystem::path dir = test::temp_dir("truncated_stl");
  {
    std::ofstream f(dir / "part.stl", std::ios::binary);
    std::string header(80, ' ');
    f.write(header.data(), 80);
    const std::uint32_t count = 10;
    f.write(reinterpret_cast<const char*>(&count), 4);
    std::string facets(50 * 3 + 7, '\0');
    f.write(facets.data(), static_cast<std::streamsize>(facets.size()));
  }
  try {
    read_mesh(dir / "part.stl");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("part.stl"), std::string::npos) << msg;
    EXPECT_NE(msg.find("facet"), std::string::npos) << msg;
  }
  std::filesystem::remove_all(dir);
}

// Every point format keeps every field by name, with nothing added (b9_training.ply's "label"
// used to be dropped by LAS and read back from XYZ as "intensity"). Text has no types: fields
// come back as Float64 there, and PCD positions as float32 (the default near the origin).
TEST(Io, EveryPointFormatKeepsEveryFieldByName) {
  const fs::path dir = test::temp_dir("io_fields_by_name");
  PointCloud cloud = test::sample_sphere(400, 3.0, Vector3d(1.0, 2.0, -4.0), 21);
  const std::size_t n = cloud.size();
  std::vector<double> label(n), deviation(n);
  for (std::size_t i = 0; i < n; ++i) {
    label[i] = static_cast<double>(i % 8);
    deviation[i] = 0.25 - 0.001 * static_cast<double>(i);
  }
  cloud.fields.add("label", 0, ScalarType::UInt8).values = label;
  cloud.fields.add("deviation", 0, ScalarType::Float64).values = deviation;
  for (const char* file : {"a.ply", "a.xyz", "a.txt", "a.csv", "a.pcd", "a.las"}) {
    SCOPED_TRACE(file);
    write_point_cloud(dir / file, cloud);
    const CloudReadResult r = read_point_cloud(dir / file);
    const PointCloud& back = r.cloud;
    ASSERT_EQ(back.size(), n);
    EXPECT_TRUE(r.warnings.empty());
    ASSERT_EQ(back.fields.size(), 2u);
    EXPECT_EQ(back.fields[0].name, "label");
    EXPECT_EQ(back.fields[1].name, "deviation");
    EXPECT_EQ(back.fields[0].values, label);
    EXPECT_EQ(back.fields[1].values, deviation);
    ASSERT_TRUE(back.has_normals());
    double worst = 0.0, worst_normal = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      worst = std::max(worst, (back.positions[i] - cloud.positions[i]).cwiseAbs().maxCoeff());
      worst_normal = std::max(worst_normal, (back.normals[i] - cloud.normals[i]).cwiseAbs().maxCoeff());
    }
    EXPECT_LE(worst, 5.0001e-5);      // LAS's 1e-4 quantum; float32 at 7 is 4.8e-7
    EXPECT_LE(worst_normal, 1e-7);   // float32 normals (PCD, LAS)
  }
  // Text keeps no types; the binary formats do.
  EXPECT_EQ(read_point_cloud(dir / "a.xyz").cloud.fields[0].type, ScalarType::Float64);
  for (const char* file : {"a.ply", "a.pcd", "a.las"}) EXPECT_EQ(read_point_cloud(dir / file).cloud.fields[0].type, ScalarType::UInt8) << file;
  // The XYZ header is a comment line other readers skip.
  EXPECT_EQ(test::read_bytes(dir / "a.xyz").substr(0, 31), "# x y z nx ny nz label deviatio");
}

// Issue 28: every attribute goes through each pair of point formats (A written, read back,
// written as B, read back) and comes back equal, or within the documented precision of the
// formats on the way (docs/formats.md, "What each format keeps"): colours are 8-bit in PLY, PCD
// and text, 16-bit in LAS, LAZ and E57; positions 1e-4 in LAS and LAZ (the default scale); the
// rest exactly. The cloud is what a LAS file gives: positions on a 1 mm grid, uint16 intensity,
// 16-bit colours, classification, returns, GPS time, normals and two extra bytes fields.
// Positions: PCD's float32 rounding (at most 1e-4 of the spacing) may add to LAS's step.
PointCloud las_like_cloud() {
  PointCloud c;
  std::mt19937 rng(28);
  std::uniform_int_distribution<int> mm(0, 900'000), channel(0, 65535), intensity(996, 57345), klass(1, 18), ret(1, 3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const std::size_t n = 300;
  auto field = [&c](const char* name, ScalarType type) -> std::vector<double>& { return c.fields.add(name, 0, type).values; };
  std::vector<double>& in = field("intensity", ScalarType::UInt16);
  std::vector<double>& cl = field("classification", ScalarType::UInt8);
  std::vector<double>& rn = field("return_number", ScalarType::UInt8);
  std::vector<double>& nr = field("number_of_returns", ScalarType::UInt8);
  std::vector<double>& gps = field("gps_time", ScalarType::Float64);
  std::vector<double>& dev = field("deviation", ScalarType::Float32);
  std::vector<double>& label = field("label", ScalarType::Int32);
  for (std::size_t i = 0; i < n; ++i) {
    c.positions.emplace_back(1000.0 + 0.001 * mm(rng), 2000.0 + 0.001 * mm(rng), 0.001 * mm(rng) / 10.0);
    const Eigen::Vector3f normal = Eigen::Vector3f(u(rng), u(rng), u(rng) + 2.0f).normalized();
    c.normals.push_back(normal.cast<double>());  // float32 values: every format keeps them
    c.colors.emplace_back(channel(rng) / 65535.0f, channel(rng) / 65535.0f, channel(rng) / 65535.0f);
    in.push_back(i == 0 ? 996 : i == 1 ? 57345 : intensity(rng));
    cl.push_back(klass(rng));
    const int returns = ret(rng);
    nr.push_back(returns);
    rn.push_back(std::min(returns, ret(rng)));
    gps.push_back(3.1e8 + 1e-6 * static_cast<double>(i * 7919));
    dev.push_back(static_cast<double>(u(rng) * 0.01f));
    label.push_back(static_cast<double>(static_cast<int>(i % 9) - 4));
  }
  return c;
}

TEST(Io, EveryAttributeGoesThroughEveryPairOfPointFormats) {
  const fs::path dir = test::temp_dir("io_attribute_matrix");
  const PointCloud source = las_like_cloud();
  const std::vector<std::string> formats = {"ply", "las", "laz", "e57", "pcd", "txt", "csv"};
  const auto eight_bit = [](const std::string& f) { return f == "ply" || f == "pcd" || f == "txt" || f == "csv"; };
  const auto quantised = [](const std::string& f) { return f == "las" || f == "laz"; };
  const double pcd_spacing = bounding_box(source.positions).diagonal() / std::sqrt(double(source.size()));
  int pairs = 0;
  for (const std::string& a : formats) {
    const fs::path first = dir / ("a." + a);
    write_point_cloud(first, source);
    const PointCloud mid = read_point_cloud(first).cloud;
    for (const std::string& b : formats) {
      SCOPED_TRACE(a + " -> " + b);
      const fs::path second = dir / (a + "_to_b." + b);
      write_point_cloud(second, mid);
      const PointCloud back = read_point_cloud(second).cloud;
      ++pairs;
      ASSERT_EQ(back.size(), source.size());
      // PCD writes float32 where that moves no point by more than 1e-4 of the spacing (diagonal / sqrt(N)).
      double position_step = quantised(a) || quantised(b) ? 0.5e-4 + 1e-9 : 1e-9;
      if (a == "pcd" || b == "pcd") position_step = std::max(position_step, 1e-4 * pcd_spacing) + 0.5e-4;
      const float colour_step = eight_bit(a) || eight_bit(b) ? 0.5f / 255.0f + 1e-6f : 0.5f / 65535.0f + 1e-7f;
      ASSERT_TRUE(back.has_normals());
      ASSERT_TRUE(back.has_colors());
      double worst_position = 0.0, worst_normal = 0.0;
      float worst_colour = 0.0f;
      for (std::size_t i = 0; i < source.size(); ++i) {
        worst_position = std::max(worst_position, (back.positions[i] - source.positions[i]).cwiseAbs().maxCoeff());
        worst_normal = std::max(worst_normal, (back.normals[i] - source.normals[i]).cwiseAbs().maxCoeff());
        worst_colour = std::max(worst_colour, (back.colors[i] - source.colors[i]).cwiseAbs().maxCoeff());
      }
      EXPECT_LE(worst_position, position_step);
      EXPECT_EQ(worst_normal, 0.0);
      EXPECT_LE(worst_colour, colour_step);
      ASSERT_EQ(back.fields.size(), source.fields.size());
      for (const ScalarField& f : source.fields) {
        const ScalarField* g = back.fields.find(f.name);
        ASSERT_NE(g, nullptr) << f.name;
        EXPECT_EQ(g->values, f.values) << f.name;
      }
    }
  }
  EXPECT_EQ(pairs, 49);
}

}  // namespace
}  // namespace pointsurf
