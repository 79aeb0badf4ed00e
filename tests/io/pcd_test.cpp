// SPDX-License-Identifier: GPL-3.0-or-later
// PCD v0.7: every encoding written then read, hand-written files (PCL's packed-float rgb,
// organized clouds with NaN points, padding and multi-count fields) and malformed input.
#include "pointsurf/io/io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::write_bytes;
using test::read_bytes;
using test::error_of;
using test::contains;

namespace fs = std::filesystem;

template <typename T>
void append(std::string& bytes, T value) {
  bytes.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// A sphere with normals, 8-bit-exact colours and one field of each storage type, with values
// that type holds exactly.
PointCloud rich_cloud(std::size_t n, const Vector3d& center = Vector3d::Zero()) {
  PointCloud cloud = test::sample_sphere(n, 1.5, center, 11);
  for (std::size_t i = 0; i < n; ++i)
    cloud.colors.emplace_back(static_cast<float>(i % 256) / 255.0f, static_cast<float>((i * 3) % 256) / 255.0f,
                              static_cast<float>((i * 5) % 256) / 255.0f);
  struct Spec { const char* name; ScalarType type; double scale, offset; };
  for (const Spec& s : {Spec{"i8", ScalarType::Int8, 1, -100}, Spec{"u8", ScalarType::UInt8, 1, 0}, Spec{"i16", ScalarType::Int16, -3, 0},
                        Spec{"u16", ScalarType::UInt16, 257, 0}, Spec{"i32", ScalarType::Int32, -70001, 0},
                        Spec{"u32", ScalarType::UInt32, 1, 4.0e9}, Spec{"i64", ScalarType::Int64, 1, -9.0e15},
                        Spec{"u64", ScalarType::UInt64, 3, 1.0e15}, Spec{"curvature", ScalarType::Float32, 0.25, 0.5},
                        Spec{"deviation", ScalarType::Float64, 1.0 / 3.0, 1e-7}}) {
    ScalarField& f = cloud.fields.add(s.name, n, s.type);
    for (std::size_t i = 0; i < n; ++i) f.values[i] = s.offset + s.scale * static_cast<double>(i % 100);
  }
  return cloud;
}

void expect_same(const PointCloud& a, const PointCloud& b, double position_tol) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.has_normals(), b.has_normals());
  ASSERT_EQ(a.has_colors(), b.has_colors());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_LE((a.positions[i] - b.positions[i]).cwiseAbs().maxCoeff(), position_tol) << "point " << i;
    if (a.has_normals()) {
      ASSERT_LE((a.normals[i] - b.normals[i]).cwiseAbs().maxCoeff(), 1e-7) << "normal " << i;  // F4
    }
    if (a.has_colors()) {
      ASSERT_TRUE(a.colors[i].isApprox(b.colors[i], 1e-6f)) << "colour " << i;
    }
  }
  ASSERT_EQ(a.fields.size(), b.fields.size());
  for (std::size_t f = 0; f < a.fields.size(); ++f) {
    EXPECT_EQ(a.fields[f].name, b.fields[f].name);
    EXPECT_EQ(a.fields[f].type, b.fields[f].type) << a.fields[f].name;
    EXPECT_EQ(a.fields[f].values, b.fields[f].values) << a.fields[f].name;
  }
}

TEST(Pcd, EveryEncodingRoundTripsNormalsColoursAndTypedFields) {
  const fs::path dir = test::temp_dir("pcd_roundtrip");
  const PointCloud cloud = rich_cloud(700);
  struct Case { const char* encoding; bool ascii, compressed; };
  for (const Case& c : {Case{"ascii", true, false}, Case{"binary", false, false}, Case{"binary_compressed", false, true}}) {
    WriteOptions options;
    options.ascii = c.ascii;
    options.pcd_compressed = c.compressed;
    options.double_precision = true;
    const fs::path path = dir / (std::string(c.encoding) + ".pcd");
    write_point_cloud(path, cloud, options);
    const std::string bytes = read_bytes(path);
    EXPECT_TRUE(contains(bytes, std::string("\nDATA ") + c.encoding + "\n")) << c.encoding;
    // PCL's layout: packed rgb declared F in binary data, U (its integer) in ascii.
    EXPECT_TRUE(contains(bytes, c.ascii ? "\nTYPE F F F F F F U " : "\nTYPE F F F F F F F ")) << c.encoding;
    const CloudReadResult r = read_point_cloud(path);
    EXPECT_EQ(r.format, "pcd");
    EXPECT_EQ(r.encoding, c.encoding);
    EXPECT_TRUE(r.warnings.empty()) << c.encoding;
    SCOPED_TRACE(c.encoding);
    expect_same(cloud, r.cloud, 0.0);  // F8 positions are exact
  }
}

TEST(Pcd, CompressedIsSmallerForRepetitiveData) {
  const fs::path dir = test::temp_dir("pcd_compressed_size");
  PointCloud cloud = test::sample_plane(5000, 1.0, 2);
  WriteOptions options;
  write_point_cloud(dir / "b.pcd", cloud, options);
  options.pcd_compressed = true;
  write_point_cloud(dir / "c.pcd", cloud, options);
  EXPECT_LT(fs::file_size(dir / "c.pcd"), fs::file_size(dir / "b.pcd"));
  expect_same(cloud, read_point_cloud(dir / "c.pcd").cloud, 1e-7);  // float32 positions (the default here)
}

TEST(Pcd, EmptyCloudRoundTripsInEveryEncoding) {
  const fs::path dir = test::temp_dir("pcd_empty");
  for (int e = 0; e < 3; ++e) {
    WriteOptions options;
    options.ascii = e == 0;
    options.pcd_compressed = e == 2;
    write_point_cloud(dir / "e.pcd", PointCloud{}, options);
    EXPECT_TRUE(read_point_cloud(dir / "e.pcd").cloud.empty()) << e;
  }
}

TEST(Pcd, HandWrittenAsciiWithPclPackedColours) {
  const fs::path dir = test::temp_dir("pcd_ascii");
  // PCL's tutorial file: rgb as the float whose bits hold the colour; newer PCL writes the
  // integer of those bits instead (last line: pure red), both are accepted.
  const std::string text =
      "# .PCD v.7 - Point Cloud Data file format\n"
      "VERSION .7\n"
      "FIELDS x y z rgb curvature\n"
      "SIZE 4 4 4 4 4\n"
      "TYPE F F F F F\n"
      "COUNT 1 1 1 1 1\n"
      "WIDTH 3\n"
      "HEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\n"
      "POINTS 3\n"
      "DATA ascii\n"
      "0.93773 0.33763 0 4.2108e+06 0.5\n"
      "0.90805 0.35641 0 4.2108e+06 0.25\n"
      "0.81915 0.32 0 16711680 0\n";
  const CloudReadResult r = read_point_cloud(write_bytes(dir / "t.pcd", text));
  EXPECT_EQ(r.encoding, "ascii");
  ASSERT_EQ(r.cloud.size(), 3u);
  // Values declared F4 are floats, as they would be in binary data.
  EXPECT_EQ(r.cloud.positions[0], Vector3d(0.93773f, 0.33763f, 0));
  const float packed = 4.2108e+06f;
  std::uint32_t bits;
  std::memcpy(&bits, &packed, 4);
  const Vector3f expected(static_cast<float>((bits >> 16) & 0xFF) / 255.0f, static_cast<float>((bits >> 8) & 0xFF) / 255.0f,
                          static_cast<float>(bits & 0xFF) / 255.0f);
  ASSERT_TRUE(r.cloud.has_colors());
  EXPECT_EQ(r.cloud.colors[0], expected);
  EXPECT_EQ(r.cloud.colors[2], Vector3f(1, 0, 0));
  ASSERT_NE(r.cloud.fields.find("curvature"), nullptr);
  EXPECT_EQ(r.cloud.fields.find("curvature")->type, ScalarType::Float32);
  EXPECT_EQ(r.cloud.fields.find("curvature")->values, (std::vector<double>{0.5, 0.25, 0}));
}

TEST(Pcd, OrganizedCloudIsFlattenedAndItsNanPointsDropped) {
  const fs::path dir = test::temp_dir("pcd_organized");
  std::string text = "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 2\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 4\nHEIGHT 3\nPOINTS 12\nDATA ascii\n";
  std::size_t valid = 0;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) {
      if ((row * 4 + col) % 4 == 1) text += "nan nan nan 0\n";
      else text += std::to_string(col) + " " + std::to_string(row) + " 1 " + std::to_string(++valid) + "\n";
    }
  const CloudReadResult r = read_point_cloud(write_bytes(dir / "o.pcd", text));
  EXPECT_EQ(r.cloud.size(), 9u);
  EXPECT_EQ(r.dropped_nonfinite, 3u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(contains(r.warnings[0], "organized cloud 4x3 flattened; 3 invalid (NaN) points dropped")) << r.warnings[0];
  EXPECT_EQ(r.cloud.positions[1], Vector3d(2, 0, 1));
  EXPECT_EQ(r.cloud.fields.find("intensity")->type, ScalarType::UInt16);
  EXPECT_EQ(r.cloud.fields.find("intensity")->values.back(), 9.0);

  ReadOptions strict;
  strict.strict = true;
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "o.pcd", strict); }), "3 points with NaN coordinates"));
}

TEST(Pcd, BinaryWithPaddingMultiCountFieldsAndRgba) {
  const fs::path dir = test::temp_dir("pcd_padding");
  std::string bytes =
      "VERSION 0.7\nFIELDS x y z _ hist rgba nx ny nz\nSIZE 8 8 8 4 2 4 4 4 4\nTYPE F F F U I U F F F\nCOUNT 1 1 1 1 3 1 1 1 1\n"
      "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n";
  for (int i = 0; i < 2; ++i) {
    append<double>(bytes, 1.0 + i);
    append<double>(bytes, 2.0);
    append<double>(bytes, 6.5e6 + 0.0001 * i);
    append<std::uint32_t>(bytes, 0xDEADBEEF);  // padding
    for (int k = 0; k < 3; ++k) append<std::int16_t>(bytes, static_cast<std::int16_t>(-10 * k - i));
    append<std::uint32_t>(bytes, 0x80FF3300u);  // alpha 0x80, rgb ff 33 00
    append<float>(bytes, 0.0f);
    append<float>(bytes, 1.0f);
    append<float>(bytes, 0.0f);
  }
  const CloudReadResult r = read_point_cloud(write_bytes(dir / "p.pcd", bytes));
  ASSERT_EQ(r.cloud.size(), 2u);
  EXPECT_EQ(r.cloud.positions[1], Vector3d(2, 2, 6.5e6 + 0.0001));
  ASSERT_TRUE(r.cloud.has_normals());
  EXPECT_EQ(r.cloud.normals[0], Vector3d(0, 1, 0));
  ASSERT_TRUE(r.cloud.has_colors());
  EXPECT_EQ(r.cloud.colors[0], Vector3f(1.0f, 0x33 / 255.0f, 0.0f));
  ASSERT_EQ(r.cloud.fields.size(), 4u);
  EXPECT_EQ(r.cloud.fields[0].name, "hist_0");
  EXPECT_EQ(r.cloud.fields[2].name, "hist_2");
  EXPECT_EQ(r.cloud.fields[2].type, ScalarType::Int16);
  EXPECT_EQ(r.cloud.fields[2].values, (std::vector<double>{-20, -21}));
  EXPECT_EQ(r.cloud.fields[3].name, "alpha");
  EXPECT_EQ(r.cloud.fields[3].values, (std::vector<double>{128, 128}));
}

TEST(Pcd, GeoreferencedOffsetsRoundTripAndSinglePrecisionIsRefused) {
  const fs::path dir = test::temp_dir("pcd_geo");
  const PointCloud cloud = rich_cloud(200, Vector3d(6.5e6, 6.5e6, 120.0));
  // The default falls back on double here, and says so.
  const WriteResult written = write_point_cloud(dir / "geo.pcd", cloud);
  ASSERT_EQ(written.notes.size(), 1u);
  EXPECT_TRUE(contains(written.notes[0], "geo.pcd: positions written as double (F8)")) << written.notes[0];
  EXPECT_TRUE(contains(read_bytes(dir / "geo.pcd"), "\nSIZE 8 8 8 "));
  expect_same(cloud, read_point_cloud(dir / "geo.pcd").cloud, 0.0);
  WriteOptions single;
  single.single_precision = true;
  EXPECT_TRUE(contains(error_of<UsageError>([&] { write_point_cloud(dir / "geo32.pcd", cloud, single); }),
                       "single precision positions would step by 0.5"));
  EXPECT_FALSE(fs::exists(dir / "geo32.pcd"));

  // Near the origin float32 is precise enough.
  const PointCloud local = rich_cloud(200);
  write_point_cloud(dir / "local32.pcd", local, single);
  EXPECT_TRUE(contains(read_bytes(dir / "local32.pcd"), "\nSIZE 4 4 4 4 4 4 4 1 1 2 2 4 4 8 8 4 8\nTYPE F F F F F F F I U I U I U I U F F\n"));
  expect_same(local, read_point_cloud(dir / "local32.pcd").cloud, 1e-6);
}

// PCL's tools and Open3D 0.16 read F8 positions as zeros: the default is F4 wherever float32
// moves no point by more than 1e-4 of the spacing, with no note.
TEST(Pcd, DefaultPositionsAreFloatWhereFloatKeepsThem) {
  const fs::path dir = test::temp_dir("pcd_float_default");
  const PointCloud cloud = rich_cloud(700);
  const WriteResult written = write_point_cloud(dir / "a.pcd", cloud);
  EXPECT_TRUE(written.notes.empty());
  EXPECT_TRUE(contains(read_bytes(dir / "a.pcd"), "\nSIZE 4 4 4 4 4 4 4 "));
  const BoundingBox box = bounding_box(cloud.positions);
  expect_same(cloud, read_point_cloud(dir / "a.pcd").cloud, 1e-4 * box.diagonal() / std::sqrt(700.0));
  WriteOptions wide;
  wide.double_precision = true;
  EXPECT_TRUE(write_point_cloud(dir / "b.pcd", cloud, wide).notes.empty());
  EXPECT_TRUE(contains(read_bytes(dir / "b.pcd"), "\nSIZE 8 8 8 4 "));
}

TEST(Pcd, TruncatedBinaryIsAnInputError) {
  const fs::path dir = test::temp_dir("pcd_truncated");
  write_point_cloud(dir / "a.pcd", test::sample_sphere(100));
  std::string bytes = read_bytes(dir / "a.pcd");
  bytes.resize(bytes.size() - 10);
  write_bytes(dir / "a.pcd", bytes);
  const std::string message = error_of<InputError>([&] { read_point_cloud(dir / "a.pcd"); });
  EXPECT_TRUE(contains(message, "a.pcd: byte ")) << message;
  EXPECT_TRUE(contains(message, "header says 100 points of 24 bytes but only 2390 bytes follow (file truncated?)")) << message;
}

TEST(Pcd, CorruptedCompressedBlockIsAnInputError) {
  const fs::path dir = test::temp_dir("pcd_corrupt");
  WriteOptions options;
  options.pcd_compressed = true;
  write_point_cloud(dir / "a.pcd", test::sample_sphere(300), options);
  const std::string good = read_bytes(dir / "a.pcd");
  const std::size_t data = good.find("DATA binary_compressed\n") + 23;

  // A back reference as the very first LZF instruction points before the output.
  std::string bad = good;
  bad[data + 8] = static_cast<char>(0xE0);
  write_bytes(dir / "b.pcd", bad);
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "b.pcd"); }), "LZF decompression failed"));

  // The uncompressed size disagreeing with POINTS.
  bad = good;
  bad[data + 4] = static_cast<char>(bad[data + 4] + 1);
  write_bytes(dir / "c.pcd", bad);
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "c.pcd"); }), "differs from POINTS 300 times 24 bytes per point"));

  // The block cut short.
  write_bytes(dir / "d.pcd", good.substr(0, good.size() - 5));
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "d.pcd"); }), "(file truncated?)"));
}

TEST(Pcd, HeaderErrorsNameTheLine) {
  const fs::path dir = test::temp_dir("pcd_header");
  auto message = [&](const std::string& text) {
    write_bytes(dir / "h.pcd", text);
    return error_of<InputError>([&] { read_point_cloud(dir / "h.pcd"); });
  };
  const std::string fields = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  EXPECT_TRUE(contains(message(fields + "WIDTH 4\nHEIGHT 3\nPOINTS 10\nDATA ascii\n"), "h.pcd: line 8: POINTS 10 differs from WIDTH*HEIGHT = 4*3 = 12"));
  EXPECT_TRUE(contains(message("VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n"),
                       "h.pcd: line 3: SIZE has 2 entries, FIELDS has 3"));
  EXPECT_TRUE(contains(message("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F Q F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n"),
                       "h.pcd: line 4: TYPE of 'y' is 'Q': expected I, U or F"));
  EXPECT_TRUE(contains(message("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 3\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n"),
                       "h.pcd: line 3: SIZE of 'z' is '3': expected 1, 2, 4 or 8"));
  EXPECT_TRUE(contains(message(fields + "WIDTH 1\nPOINTS 1\nDATA zipped\n"), "h.pcd: line 8: unknown DATA 'zipped'"));
  EXPECT_TRUE(contains(message(fields + "WIDTH 1\nPOINTS 1\n"), "header ends at line 7 without a DATA line"));
  EXPECT_TRUE(contains(message(fields + "WIDTH 1\nFOO 3\nDATA ascii\n"), "h.pcd: line 7: unknown header entry 'FOO'"));
  EXPECT_TRUE(contains(message("VERSION 0.7\nFIELDS a b c\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n1 2 3\n"), "FIELDS has no x, y and z"));
  EXPECT_TRUE(contains(message(fields + "WIDTH 2\nDATA ascii\n1 2 3\n4 5\n"), "h.pcd: line 9: point 1: expected 3 values, got 2"));
  EXPECT_TRUE(contains(message(fields + "WIDTH 2\nDATA ascii\n1 2 3\n4 5 x\n"), "h.pcd: line 9, value 3 (z): 'x' is not a number"));
  EXPECT_TRUE(contains(message(fields + "WIDTH 3\nDATA ascii\n1 2 3\n"), "point 1: expected 3 points (POINTS), file ends after 1"));
}

TEST(Pcd, HugePointCountInATinyFileIsAnInputError) {
  const fs::path dir = test::temp_dir("pcd_huge");
  const std::string header = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1000000000000\nHEIGHT 1\nPOINTS 1000000000000\n";
  write_bytes(dir / "b.pcd", header + "DATA binary\n" + std::string(24, '\0'));
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "b.pcd"); }),
                       "header says 1000000000000 points of 12 bytes but only 24 bytes follow"));
  write_bytes(dir / "a.pcd", header + "DATA ascii\n1 2 3\n");
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "a.pcd"); }), "file ends after 1"));
  std::string compressed = header + "DATA binary_compressed\n";
  append<std::uint32_t>(compressed, 4);
  append<std::uint32_t>(compressed, 0xFFFFFFF0u);
  compressed += "abcd";
  write_bytes(dir / "c.pcd", compressed);
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "c.pcd"); }), "uncompressed size 4294967280 differs"));
  // Sizes that agree with the header but that 4 bytes of LZF cannot produce.
  std::string expand = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 100000000\nPOINTS 100000000\nDATA binary_compressed\n";
  append<std::uint32_t>(expand, 4);
  append<std::uint32_t>(expand, 1200000000u);
  expand += "abcd";
  write_bytes(dir / "d.pcd", expand);
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "d.pcd"); }), "4 compressed bytes cannot expand to 1200000000 bytes"));
}

TEST(Pcd, WriterRefusesFieldNamesPcdCannotHold) {
  const fs::path dir = test::temp_dir("pcd_names");
  PointCloud cloud = test::sample_plane(4, 1.0, 1);
  cloud.fields.add("two words", cloud.size());
  EXPECT_TRUE(contains(error_of<UsageError>([&] { write_point_cloud(dir / "a.pcd", cloud); }), "field 'two words' cannot be written to PCD"));
  cloud.fields.remove("two words");
  cloud.fields.add("rgb", cloud.size());
  EXPECT_TRUE(contains(error_of<UsageError>([&] { write_point_cloud(dir / "a.pcd", cloud); }), "the name is a PCD standard field"));
}

}  // namespace
}  // namespace pointsurf
