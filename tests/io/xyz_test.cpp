// SPDX-License-Identifier: GPL-3.0-or-later
// XYZ-family text clouds (.xyz, .txt, .pts, .csv): headers, PTS count lines, separators,
// column specs, the column-count defaults, error messages and write-then-read.
#include "pointsurf/io/io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <random>
#include <string>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "support/cli_run.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::error_of;
using test::contains;

namespace fs = std::filesystem;

using test::read_bytes;
using test::write_bytes;

CloudReadResult read_text_cloud(const fs::path& dir, const std::string& file, const std::string& text, const std::string& columns = {}) {
  ReadOptions options;
  options.columns = columns;
  return read_point_cloud(write_bytes(dir / file, text), options);
}

// Colours that 8-bit storage keeps exactly.
void set_byte_colours(PointCloud& cloud) {
  cloud.colors.clear();
  for (std::size_t i = 0; i < cloud.size(); ++i)
    cloud.colors.emplace_back(static_cast<float>(i % 256) / 255.0f, static_cast<float>((i * 7) % 256) / 255.0f,
                              static_cast<float>((i * 13) % 256) / 255.0f);
}

TEST(Xyz, PlainThreeColumns) {
  const fs::path dir = test::temp_dir("xyz_plain");
  const CloudReadResult r = read_text_cloud(dir, "a.xyz", "1 2 3\n4.5 -5e2 6\n+7 .5 1e-320\n");
  EXPECT_EQ(r.format, "xyz");
  EXPECT_EQ(r.encoding, "ascii");
  ASSERT_EQ(r.cloud.size(), 3u);
  EXPECT_EQ(r.cloud.positions[1], Vector3d(4.5, -500.0, 6.0));
  EXPECT_EQ(r.cloud.positions[2], Vector3d(7.0, 0.5, 1e-320));  // a '+' sign and a denormal
  EXPECT_FALSE(r.cloud.has_normals());
  EXPECT_FALSE(r.cloud.has_colors());
  EXPECT_TRUE(r.cloud.fields.empty());
  EXPECT_TRUE(r.warnings.empty());
}

TEST(Xyz, HeaderNamesGiveTheColumns) {
  const fs::path dir = test::temp_dir("xyz_header");
  const CloudReadResult r = read_text_cloud(dir, "a.txt", "X Y Z Intensity Nx Ny Nz Label\n1 2 3 40 0 0 1 7\n4 5 6 41 1 0 0 8\n");
  ASSERT_EQ(r.cloud.size(), 2u);
  EXPECT_EQ(r.cloud.positions[1], Vector3d(4, 5, 6));
  ASSERT_TRUE(r.cloud.has_normals());
  EXPECT_EQ(r.cloud.normals[0], Vector3d(0, 0, 1));
  ASSERT_NE(r.cloud.fields.find("intensity"), nullptr);
  EXPECT_EQ(r.cloud.fields.find("intensity")->values, (std::vector<double>{40, 41}));
  ASSERT_NE(r.cloud.fields.find("Label"), nullptr);  // other names keep their spelling
  EXPECT_EQ(r.cloud.fields.find("Label")->values, (std::vector<double>{7, 8}));
  EXPECT_TRUE(r.warnings.empty());
}

TEST(Xyz, CloudCompareHeaderWithSlashesAndColourNames) {
  const fs::path dir = test::temp_dir("xyz_cc_header");
  const CloudReadResult r = read_text_cloud(dir, "a.txt", "//X,Y,Z,Red,Green,Blue\n1,2,3,255,0,51\n");
  ASSERT_EQ(r.cloud.size(), 1u);
  ASSERT_TRUE(r.cloud.has_colors());
  EXPECT_FLOAT_EQ(r.cloud.colors[0].x(), 1.0f);
  EXPECT_FLOAT_EQ(r.cloud.colors[0].y(), 0.0f);
  EXPECT_FLOAT_EQ(r.cloud.colors[0].z(), 0.2f);
}

TEST(Xyz, HeaderWithIncompleteColourGroupKeepsThoseColumnsAsFields) {
  const fs::path dir = test::temp_dir("xyz_partial");
  const CloudReadResult r = read_text_cloud(dir, "a.csv", "x,y,z,r,g\n1,2,3,4,5\n");
  EXPECT_FALSE(r.cloud.has_colors());
  ASSERT_NE(r.cloud.fields.find("r"), nullptr);
  EXPECT_EQ(r.cloud.fields.find("g")->values, std::vector<double>{5});
}

TEST(Xyz, TitleLineIsIgnoredWithAWarning) {
  const fs::path dir = test::temp_dir("xyz_title");
  const CloudReadResult r = read_text_cloud(dir, "a.xyz", "exported by scanner\n1 2 3\n");
  ASSERT_EQ(r.cloud.size(), 1u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(contains(r.warnings[0], "line 1: first line is not a header")) << r.warnings[0];
}

TEST(Xyz, PtsCountLine) {
  const fs::path dir = test::temp_dir("xyz_pts");
  const std::string body = "1 2 3 -100 255 0 0\n4 5 6 200 0 255 0\n7 8 9 300 0 0 255\n";
  const CloudReadResult r = read_text_cloud(dir, "a.pts", "3\n" + body);
  ASSERT_EQ(r.cloud.size(), 3u);
  ASSERT_EQ(r.warnings.size(), 1u);  // the layout taken
  EXPECT_TRUE(contains(r.warnings[0], "columns taken as x y z intensity r g b (PTS")) << r.warnings[0];
  EXPECT_EQ(r.cloud.positions[2], Vector3d(7, 8, 9));

  const CloudReadResult bad = read_text_cloud(dir, "b.pts", "5\n" + body);
  ASSERT_EQ(bad.cloud.size(), 3u);
  ASSERT_EQ(bad.warnings.size(), 2u);
  EXPECT_TRUE(contains(bad.warnings[1], "line 1: point count 5 differs from the 3 points in the file")) << bad.warnings[1];
}

TEST(Xyz, DefaultSevenColumnsArePtsIntensityThenColour) {
  const fs::path dir = test::temp_dir("xyz_seven");
  const CloudReadResult r = read_text_cloud(dir, "a.pts", "1 2 3 -100 255 0 0\n4 5 6 200 0 255 0\n");
  ASSERT_TRUE(r.cloud.has_colors());
  EXPECT_EQ(r.cloud.colors[0], Vector3f(1, 0, 0));
  EXPECT_EQ(r.cloud.colors[1], Vector3f(0, 1, 0));
  ASSERT_NE(r.cloud.fields.find("intensity"), nullptr);
  EXPECT_EQ(r.cloud.fields.find("intensity")->values, (std::vector<double>{-100, 200}));
}

TEST(Xyz, CommaAndSemicolonSeparators) {
  const fs::path dir = test::temp_dir("xyz_sep");
  const CloudReadResult comma = read_text_cloud(dir, "a.csv", "x,y,z\n1,2,3\n4, 5, 6\n");
  ASSERT_EQ(comma.cloud.size(), 2u);
  EXPECT_EQ(comma.cloud.positions[1], Vector3d(4, 5, 6));
  const CloudReadResult semi = read_text_cloud(dir, "b.csv", "\"x\";\"y\";\"z\";\"class\"\n1;2;3;9\n");
  ASSERT_EQ(semi.cloud.size(), 1u);
  EXPECT_EQ(semi.cloud.positions[0], Vector3d(1, 2, 3));
  ASSERT_NE(semi.cloud.fields.find("class"), nullptr);
  EXPECT_EQ(semi.cloud.fields.find("class")->values, std::vector<double>{9});
}

TEST(Xyz, ColumnSpecOverridesWithSkippedColumns) {
  const fs::path dir = test::temp_dir("xyz_spec");
  const CloudReadResult r = read_text_cloud(dir, "a.xyz", "t12:30 1 2 3 0.5\nt12:31 4 5 6 0.25\n", "_,x,y,z,i");
  ASSERT_EQ(r.cloud.size(), 2u);
  EXPECT_EQ(r.cloud.positions[0], Vector3d(1, 2, 3));
  EXPECT_EQ(r.cloud.positions[1], Vector3d(4, 5, 6));
  ASSERT_EQ(r.cloud.fields.size(), 1u);
  EXPECT_EQ(r.cloud.fields[0].name, "intensity");
  EXPECT_EQ(r.cloud.fields[0].values, (std::vector<double>{0.5, 0.25}));

  // Order other than x y z, a header that the spec overrides, a named field.
  const CloudReadResult s = read_text_cloud(dir, "b.csv", "a,b,c,d\n3,2,1,7\n", "z,y,x,weight");
  EXPECT_EQ(s.cloud.positions[0], Vector3d(1, 2, 3));
  EXPECT_EQ(s.cloud.fields.find("weight")->values, std::vector<double>{7});

  // A spec shorter than the data skips the remaining columns with a warning.
  const CloudReadResult t = read_text_cloud(dir, "c.xyz", "1 2 3 4 5\n", "x,y,z");
  EXPECT_TRUE(t.cloud.fields.empty());
  ASSERT_EQ(t.warnings.size(), 1u);
  EXPECT_TRUE(contains(t.warnings[0], "columns 4-5 are not in the column spec")) << t.warnings[0];
}

TEST(Xyz, BadColumnSpecsAreUsageErrors) {
  const fs::path dir = test::temp_dir("xyz_spec_bad");
  write_bytes(dir / "a.xyz", "1 2 3 4\n");
  ReadOptions options;
  options.columns = "x,y,_,i";
  EXPECT_TRUE(contains(error_of<UsageError>([&] { read_point_cloud(dir / "a.xyz", options); }),
                       "column spec 'x,y,_,i': x, y and z must all be given"));
  options.columns = "x,y,z,nx";
  EXPECT_TRUE(contains(error_of<UsageError>([&] { read_point_cloud(dir / "a.xyz", options); }), "nx, ny and nz must all be given"));
  options.columns = "x,y,z,x";
  EXPECT_TRUE(contains(error_of<UsageError>([&] { read_point_cloud(dir / "a.xyz", options); }), "columns 1 and 4 both mean 'x'"));
  options.columns = "x,y,z,a,a";
  EXPECT_TRUE(contains(error_of<UsageError>([&] { read_point_cloud(dir / "a.xyz", options); }), "field 'a' appears twice"));
  // A spec longer than the data is an InputError about the data.
  options.columns = "x,y,z,nx,ny,nz";
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "a.xyz", options); }),
                       "a.xyz: line 1: expected 6 values (column spec 'x,y,z,nx,ny,nz'), got 4"));
}

TEST(Xyz, SixColumnsAreNormalsWhenUnitVectorsElseColours) {
  const fs::path dir = test::temp_dir("xyz_six");
  const CloudReadResult n = read_text_cloud(dir, "n.xyz", "0 0 0 0 0 1\n1 0 0 0.6 0.8 0\n2 0 0 0 0 0\n");
  ASSERT_TRUE(n.cloud.has_normals());
  EXPECT_FALSE(n.cloud.has_colors());
  EXPECT_EQ(n.cloud.normals[1], Vector3d(0.6, 0.8, 0));

  const CloudReadResult c = read_text_cloud(dir, "c.xyz", "0 0 0 255 128 0\n1 0 0 0 0 0\n");
  ASSERT_TRUE(c.cloud.has_colors());
  EXPECT_FALSE(c.cloud.has_normals());
  EXPECT_FLOAT_EQ(c.cloud.colors[0].y(), 128.0f / 255.0f);

  // Values <= 1 that are not unit vectors: colours as [0, 1] floats.
  const CloudReadResult f = read_text_cloud(dir, "f.xyz", "0 0 0 0.5 0.25 0\n");
  ASSERT_TRUE(f.cloud.has_colors());
  EXPECT_EQ(f.cloud.colors[0], Vector3f(0.5f, 0.25f, 0.0f));

  // Values above 255: 16-bit colours.
  const CloudReadResult w = read_text_cloud(dir, "w.xyz", "0 0 0 65535 0 13107\n");
  ASSERT_TRUE(w.cloud.has_colors());
  EXPECT_FLOAT_EQ(w.cloud.colors[0].x(), 1.0f);
  EXPECT_FLOAT_EQ(w.cloud.colors[0].z(), 0.2f);
}

TEST(Xyz, OtherColumnCountsDefaults) {
  const fs::path dir = test::temp_dir("xyz_counts");
  const CloudReadResult four = read_text_cloud(dir, "a.xyz", "1 2 3 9\n");
  EXPECT_EQ(four.cloud.fields.find("intensity")->values, std::vector<double>{9});
  const CloudReadResult five = read_text_cloud(dir, "b.xyz", "1 2 3 8 9\n");
  ASSERT_EQ(five.cloud.fields.size(), 2u);
  EXPECT_EQ(five.cloud.fields[0].name, "field3");
  EXPECT_EQ(five.cloud.fields[1].name, "field4");
  EXPECT_EQ(five.cloud.fields[1].values, std::vector<double>{9});
  const CloudReadResult ten = read_text_cloud(dir, "c.xyz", "1 2 3 0 1 0 255 255 255 42\n");
  EXPECT_TRUE(ten.cloud.has_normals());
  EXPECT_TRUE(ten.cloud.has_colors());
  EXPECT_EQ(ten.cloud.fields.find("field9")->values, std::vector<double>{42});
}

// Issue 28: CloudCompare's default ASCII export (X Y Z R G B SF Nx Ny Nz, no header) was read
// with the colours as normals and the normals clamped into colours, exit 0, no warning. Layouts
// of headerless text are now told apart by their values: colours are integers 0..255, normals
// unit vectors.
std::string cloudcompare_export(std::size_t n, bool scalar_field) {
  std::mt19937 rng(28);
  std::uniform_int_distribution<int> channel(0, 255);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::string text;
  for (std::size_t i = 0; i < n; ++i) {
    const Vector3d normal = Vector3d(u(rng), u(rng), u(rng) + 2.0).normalized();
    text += fmt::format("{:.6f} {:.6f} {:.6f} {} {} {}", u(rng), u(rng), u(rng), channel(rng), channel(rng), channel(rng));
    if (scalar_field) text += fmt::format(" {:.6f}", u(rng) * 100.0);
    text += fmt::format(" {:.6f} {:.6f} {:.6f}\n", normal.x(), normal.y(), normal.z());
  }
  return text;
}

TEST(Xyz, CloudCompareDefaultExportIsReadAsColoursScalarFieldAndNormals) {
  const fs::path dir = test::temp_dir("xyz_cloudcompare");
  const std::string text = cloudcompare_export(200, true);
  const CloudReadResult r = read_text_cloud(dir, "cc.txt", text);
  ASSERT_EQ(r.cloud.size(), 200u);
  ASSERT_TRUE(r.cloud.has_colors());
  ASSERT_TRUE(r.cloud.has_normals());
  ASSERT_EQ(r.cloud.fields.size(), 1u);
  EXPECT_EQ(r.cloud.fields[0].name, "field6");
  // Line 1, by construction: the colours are its columns 4-6 over 255, the normal its last three.
  const std::string first = text.substr(0, text.find('\n'));
  std::vector<double> v;
  for (std::size_t at = 0, end; at < first.size(); at = end + 1) {
    end = std::min(first.find(' ', at), first.size());
    v.push_back(std::stod(first.substr(at, end - at)));
  }
  EXPECT_TRUE(r.cloud.colors[0].isApprox(Vector3f(float(v[3]), float(v[4]), float(v[5])) / 255.0f, 1e-6f)) << r.cloud.colors[0].transpose();
  EXPECT_EQ(r.cloud.fields[0].values[0], v[6]);
  EXPECT_EQ(r.cloud.normals[0], Vector3d(v[7], v[8], v[9]));
  for (const Vector3d& n : r.cloud.normals) EXPECT_NEAR(n.norm(), 1.0, 1e-5);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(contains(r.warnings[0], "no header: columns taken as x y z r g b field6 nx ny nz (CloudCompare's default ASCII export"))
      << r.warnings[0];
  EXPECT_TRUE(contains(r.warnings[0], "give --columns")) << r.warnings[0];

  // Without the scalar field (9 columns), colours then normals: not pointsurf's normals then colours.
  const CloudReadResult nine = read_text_cloud(dir, "cc9.txt", cloudcompare_export(50, false));
  ASSERT_TRUE(nine.cloud.has_colors());
  for (const Vector3d& n : nine.cloud.normals) EXPECT_NEAR(n.norm(), 1.0, 1e-5);
  EXPECT_TRUE(contains(nine.warnings.at(0), "x y z r g b nx ny nz (CloudCompare: colours, then normals)")) << nine.warnings.at(0);

  // Through the command line: exit 0, the layout named on stderr, the colours and normals in the output.
  const test::RunResult run = test::run_cli(fmt::format("convert {} {}", (dir / "cc.txt").string(), (dir / "cc.ply").string()), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(contains(run.err, "columns taken as x y z r g b field6 nx ny nz")) << run.err;
  const PointCloud ply = read_point_cloud(dir / "cc.ply").cloud;
  EXPECT_TRUE(ply.colors[0].isApprox(r.cloud.colors[0], 1e-6f));
  EXPECT_EQ(ply.normals[0], r.cloud.normals[0]);
}

TEST(Xyz, TwoLayoutsThatFitEquallyAreRefusedNamingColumns) {
  const fs::path dir = test::temp_dir("xyz_ambiguous");
  // x y z i r g b (PTS) or x y z r g b SF (CloudCompare)? With intensities 0..255 both fit.
  const std::string text = "0 0 0 10 20 30 40\n1 0 0 200 0 255 7\n0 1 0 55 66 77 88\n";
  const std::string message = error_of<InputError>([&] { read_text_cloud(dir, "a.txt", text); });
  EXPECT_TRUE(contains(message, "a.txt: line 1: the 7 columns without a header fit two layouts by their values: x y z intensity r g b")) << message;
  EXPECT_TRUE(contains(message, "x y z r g b field6")) << message;
  EXPECT_TRUE(contains(message, "say which with --columns (e.g. --columns x,y,z,intensity,r,g,b)")) << message;
  const test::RunResult run = test::run_cli(fmt::format("convert {} {}", (dir / "a.txt").string(), (dir / "a.ply").string()), dir);
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_TRUE(contains(run.err, "--columns")) << run.err;
  EXPECT_FALSE(fs::exists(dir / "a.ply"));
  // Said with --columns, or in a .pts file (whose format is x y z i r g b), it is read.
  EXPECT_EQ(read_text_cloud(dir, "a.txt", text, "x,y,z,r,g,b,sf").cloud.fields.find("sf")->values, (std::vector<double>{40, 7, 88}));
  const CloudReadResult pts = read_text_cloud(dir, "a.pts", text);
  EXPECT_EQ(pts.cloud.fields.find("intensity")->values, (std::vector<double>{10, 200, 55}));
  // An intensity that no colour can be (negative, or above 255 with 8-bit colours) decides it.
  EXPECT_TRUE(read_text_cloud(dir, "b.txt", "0 0 0 -10 20 30 40\n").cloud.fields.contains("intensity"));
}

TEST(Xyz, ColumnsThatFitNoLayoutAreFieldsNotClampedColours) {
  const fs::path dir = test::temp_dir("xyz_no_layout");
  // Six columns, neither unit vectors nor colours: before, read as colours clamped to [0, 1].
  const CloudReadResult r = read_text_cloud(dir, "a.xyz", "0 0 0 300.5 -2 7\n1 0 0 12 0.5 9\n");
  EXPECT_FALSE(r.cloud.has_colors());
  EXPECT_FALSE(r.cloud.has_normals());
  ASSERT_EQ(r.cloud.fields.size(), 3u);
  EXPECT_EQ(r.cloud.fields[0].name, "field3");
  EXPECT_EQ(r.cloud.fields[0].values, (std::vector<double>{300.5, 12}));
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(contains(r.warnings[0], "columns taken as x y z field3 field4 field5 (no known layout fits")) << r.warnings[0];
  // Axis-aligned unit normals are integers 0 and 1 too: unit vectors win over colours that dark.
  const CloudReadResult n = read_text_cloud(dir, "n.xyz", "0 0 0 0 0 1\n1 0 0 0 1 0\n");
  EXPECT_TRUE(n.cloud.has_normals());
}

TEST(Xyz, ErrorsNameLineAndColumn) {
  const fs::path dir = test::temp_dir("xyz_errors");
  write_bytes(dir / "scan.xyz", "1 2 3 0 0 1\n# comment\n4 5 6 0 0 1\n7 8 9 0\n");
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "scan.xyz"); }), "scan.xyz: line 4: expected 6 values, got 4"));
  write_bytes(dir / "bad.xyz", "1 2 3\n4 5 abc\n");
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "bad.xyz"); }), "bad.xyz: line 2, column 3: 'abc' is not a number"));
  write_bytes(dir / "two.xyz", "1 2\n3 4\n");
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "two.xyz"); }), "two.xyz: line 1: expected at least 3 values (x y z), got 2"));
  write_bytes(dir / "dup.csv", "x,y,z,x\n1,2,3,4\n");
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "dup.csv"); }), "dup.csv: line 1: header: columns 1 and 4 both mean 'x'"));
}

TEST(Xyz, CrlfBlankAndCommentLines) {
  const fs::path dir = test::temp_dir("xyz_crlf");
  const CloudReadResult r = read_text_cloud(dir, "a.xyz", "# scanner output\r\n\r\n1 2 3\r\n// note\r\n   \r\n4 5 6\r\n\r\n");
  ASSERT_EQ(r.cloud.size(), 2u);
  EXPECT_EQ(r.cloud.positions[1], Vector3d(4, 5, 6));
  write_bytes(dir / "b.xyz", "1 2 3\r\n\r\n4 5\r\n");
  EXPECT_TRUE(contains(error_of<InputError>([&] { read_point_cloud(dir / "b.xyz"); }), "b.xyz: line 3: expected 3 values, got 2"));
}

TEST(Xyz, NanCoordinatesAreDroppedAndCounted) {
  const fs::path dir = test::temp_dir("xyz_nan");
  const CloudReadResult r = read_text_cloud(dir, "a.xyz", "1 2 3\nnan nan nan\n4 5 6\n");
  EXPECT_EQ(r.cloud.size(), 2u);
  EXPECT_EQ(r.dropped_nonfinite, 1u);
}

TEST(Xyz, HeaderOnlyFileIsAnEmptyCloud) {
  const fs::path dir = test::temp_dir("xyz_empty");
  const CloudReadResult r = read_text_cloud(dir, "a.csv", "x,y,z\n");
  EXPECT_TRUE(r.cloud.empty());
}

TEST(Xyz, ReadsTheShippedKittenScan) {
  const CloudReadResult r = read_point_cloud(test::data_path("kitten.xyz"));
  EXPECT_EQ(r.cloud.size(), 5210u);
  ASSERT_TRUE(r.cloud.has_normals());
  for (const Vector3d& n : r.cloud.normals) EXPECT_NEAR(n.norm(), 1.0, 1e-4);
}

TEST(Xyz, RoundTripKeepsPositionsNormalsColours) {
  const fs::path dir = test::temp_dir("xyz_roundtrip");
  PointCloud cloud = test::sample_sphere(500, 2.0, Vector3d(1, -2, 3), 5);
  set_byte_colours(cloud);
  for (const char* file : {"a.xyz", "a.txt", "a.pts", "a.csv"}) {
    write_point_cloud(dir / file, cloud);
    const CloudReadResult r = read_point_cloud(dir / file);
    ASSERT_EQ(r.cloud.size(), cloud.size()) << file;
    ASSERT_TRUE(r.cloud.has_normals()) << file;
    ASSERT_TRUE(r.cloud.has_colors()) << file;
    // .xyz, .txt and .csv name their columns; .pts cannot (its first line is the count), so its
    // layout is inferred from the values and named in a warning.
    EXPECT_EQ(r.warnings.size(), std::string(file) == "a.pts" ? 1u : 0u) << file;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      ASSERT_EQ(r.cloud.positions[i], cloud.positions[i]) << file << " point " << i;  // shortest round-trip text is exact
      ASSERT_EQ(r.cloud.normals[i], cloud.normals[i]) << file;
      ASSERT_TRUE(r.cloud.colors[i].isApprox(cloud.colors[i], 1e-6f)) << file;
    }
  }
  EXPECT_EQ(read_bytes(dir / "a.pts").substr(0, 4), "500\n");
  EXPECT_EQ(read_bytes(dir / "a.csv").substr(0, 18), "x,y,z,nx,ny,nz,r,g");
  EXPECT_EQ(read_bytes(dir / "a.xyz").substr(0, 23), "# x y z nx ny nz r g b\n");  // a comment to other readers
}

TEST(Xyz, CsvRoundTripKeepsNamedFields) {
  const fs::path dir = test::temp_dir("xyz_csv_fields");
  PointCloud cloud = test::sample_plane(200, 1.0, 3);
  ScalarField& label = cloud.fields.add("label", cloud.size(), ScalarType::Int32);
  ScalarField& dev = cloud.fields.add("deviation", cloud.size(), ScalarType::Float64);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    label.values[i] = static_cast<double>(i % 5) - 2.0;
    dev.values[i] = 1e-3 * static_cast<double>(i) / 7.0;
  }
  write_point_cloud(dir / "a.csv", cloud);
  const CloudReadResult r = read_point_cloud(dir / "a.csv");
  ASSERT_EQ(r.cloud.fields.size(), 2u);
  EXPECT_EQ(r.cloud.fields[0].name, "label");
  EXPECT_EQ(r.cloud.fields[0].values, cloud.fields[0].values);
  EXPECT_EQ(r.cloud.fields[1].name, "deviation");
  EXPECT_EQ(r.cloud.fields[1].values, cloud.fields[1].values);
  EXPECT_TRUE(r.cloud.has_normals());
}

TEST(Xyz, PtsLayoutRoundTripOfOneFieldWithColours) {
  const fs::path dir = test::temp_dir("xyz_pts_layout");
  PointCloud cloud = test::sample_plane(50, 1.0, 4);
  cloud.normals.clear();
  set_byte_colours(cloud);
  ScalarField& intensity = cloud.fields.add("intensity", cloud.size(), ScalarType::UInt16);
  for (std::size_t i = 0; i < cloud.size(); ++i) intensity.values[i] = static_cast<double>(3 * i);
  write_point_cloud(dir / "a.pts", cloud);
  const CloudReadResult r = read_point_cloud(dir / "a.pts");
  ASSERT_TRUE(r.cloud.has_colors());
  ASSERT_NE(r.cloud.fields.find("intensity"), nullptr);
  EXPECT_EQ(r.cloud.fields.find("intensity")->values, intensity.values);
  for (std::size_t i = 0; i < cloud.size(); ++i) ASSERT_TRUE(r.cloud.colors[i].isApprox(cloud.colors[i], 1e-6f));
}

TEST(Xyz, GeoreferencedOffsetsRoundTrip) {
  const fs::path dir = test::temp_dir("xyz_geo");
  PointCloud cloud = test::sample_sphere(300, 10.0, Vector3d(6.5e6, 6.5e6, 300.0), 9);
  WriteOptions options;
  options.precision = 12;  // 12 significant digits still hold 0.1 mm at 6,500,000 m
  write_point_cloud(dir / "geo.xyz", cloud, options);
  const CloudReadResult r = read_point_cloud(dir / "geo.xyz");
  ASSERT_EQ(r.cloud.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) ASSERT_LE((r.cloud.positions[i] - cloud.positions[i]).cwiseAbs().maxCoeff(), 1e-4);
}

TEST(Xyz, CsvWriterRefusesFieldNamesThatWouldNotReadBack) {
  const fs::path dir = test::temp_dir("xyz_csv_names");
  PointCloud cloud = test::sample_plane(3, 1.0, 2);
  cloud.fields.add("red", cloud.size());
  EXPECT_TRUE(contains(error_of<UsageError>([&] { write_point_cloud(dir / "a.csv", cloud); }), "field 'red' cannot be a CSV column name"));
  cloud.fields.remove("red");
  cloud.fields.add("a b", cloud.size());
  EXPECT_TRUE(contains(error_of<UsageError>([&] { write_point_cloud(dir / "a.csv", cloud); }), "field 'a b'"));
  EXPECT_FALSE(fs::exists(dir / "a.csv"));
}

}  // namespace
}  // namespace pointsurf
