// SPDX-License-Identifier: GPL-3.0-or-later
// The phases of write_e57 (io/detail/e57_writer.h), each run alone on a few points whose
// bytes and XML are known by construction.
#include "io/detail/e57_writer.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "io/detail/e57_format.h"
#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using io::detail::E57Writer;
using io::detail::OutField;
using test::contains;
using test::expect_error;

const std::filesystem::path kPath = "out.e57";

PointCloud points(std::vector<Vector3d> positions) {
  PointCloud c;
  c.positions = std::move(positions);
  return c;
}

void add_field(PointCloud& cloud, const std::string& name, std::vector<double> values, ScalarType type = ScalarType::Float64) {
  cloud.fields.add(name, values.size(), type).values = std::move(values);
}

template <typename T>
std::vector<unsigned char> bytes_of(const std::vector<T>& values) {
  std::vector<unsigned char> out(values.size() * sizeof(T));
  std::memcpy(out.data(), values.data(), out.size());
  return out;
}

template <typename T>
T read_at(std::string_view bytes, std::size_t offset) {
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof(T));
  return v;
}

TEST(E57WriterPhases, ScaleMustBePositiveAndFinite) {
  const PointCloud cloud = points({{0, 0, 0}});
  std::vector<std::string> notes;
  for (const double scale : {0.0, -1.0, std::numeric_limits<double>::infinity()}) {
    WriteOptions options;
    options.e57_scale = scale;
    expect_error<UsageError>([&] { E57Writer e57(kPath, cloud, options, notes); }, "must be positive");
  }
}

TEST(E57WriterPhases, PointsAreGroupedByTheirScanNumber) {
  PointCloud cloud = points({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}});
  const WriteOptions options;
  std::vector<std::string> notes;
  {
    E57Writer e57(kPath, cloud, options, notes);
    e57.group_scans();
    EXPECT_EQ(e57.groups, (std::map<long long, std::vector<std::size_t>>{{0, {0, 1, 2, 3}}}));
  }
  add_field(cloud, "scan", {1, 0, 1, 4});
  {
    E57Writer e57(kPath, cloud, options, notes);
    e57.group_scans();
    EXPECT_EQ(e57.groups, (std::map<long long, std::vector<std::size_t>>{{0, {1}}, {1, {0, 2}}, {4, {3}}}));
  }
  cloud.fields.find("scan")->values[2] = 0.5;
  E57Writer e57(kPath, cloud, options, notes);
  expect_error<UsageError>([&] { e57.group_scans(); }, "point 2: field scan = 0.5 is not a scan number");
  // An empty cloud is one empty scan.
  const PointCloud none;
  E57Writer empty(kPath, none, options, notes);
  empty.group_scans();
  EXPECT_EQ(empty.groups, (std::map<long long, std::vector<std::size_t>>{{0, {}}}));
}

TEST(E57WriterPhases, IntensityLimitsAreTheTypesRangeTheUnitRangeOrTheFieldsRange) {
  const WriteOptions options;
  std::vector<std::string> notes;
  struct Limits {
    double lo, hi;
    bool integer;
    bool operator==(const Limits&) const = default;
  };
  const auto limits = [&](std::vector<double> values, ScalarType type = ScalarType::Float64) {
    PointCloud cloud = points(std::vector<Vector3d>(values.size(), Vector3d::Zero()));
    add_field(cloud, "intensity", std::move(values), type);
    E57Writer e57(kPath, cloud, options, notes);
    e57.set_intensity_limits();
    return Limits{e57.intensity_lo, e57.intensity_hi, e57.intensity_integer};
  };
  EXPECT_EQ(limits({0.2, 0.8}), (Limits{0.0, 1.0, false}));
  EXPECT_EQ(limits({3.0, -2.0, 1.0}), (Limits{-2.0, 3.0, false}));
  EXPECT_EQ(limits({5.0, 5.0}), (Limits{5.0, 6.0, false}));  // a constant field gets a unit-wide range
  EXPECT_EQ(limits({996, 57345}, ScalarType::UInt16), (Limits{0.0, 65535.0, true}));  // LAS's intensity
  EXPECT_EQ(limits({7, 200}, ScalarType::UInt8), (Limits{0.0, 255.0, true}));
  EXPECT_EQ(limits({-40, 9}, ScalarType::Int32), (Limits{-40.0, 9.0, true}));
  EXPECT_TRUE(notes.empty());  // the values are stored as they are: nothing to say
}

TEST(E57WriterPhases, ColourLimitsAreEightBitUnlessAColourNeedsSixteen) {
  PointCloud cloud = points({{0, 0, 0}, {1, 0, 0}});
  cloud.colors = {Vector3f(0, 128 / 255.0f, 1), Vector3f(7 / 255.0f, 0, 0)};
  const WriteOptions options;
  std::vector<std::string> notes;
  E57Writer e57(kPath, cloud, options, notes);
  e57.set_color_limits();
  EXPECT_EQ(e57.color_maximum, 255);
  EXPECT_EQ(e57.color_fields({0, 1})[1].bytes, (std::vector<unsigned char>{128, 0}));
  cloud.colors[1].x() = 1000 / 65535.0f;
  e57.set_color_limits();
  EXPECT_EQ(e57.color_maximum, 65535);
  const std::vector<OutField> fields = e57.color_fields({0, 1});
  EXPECT_EQ(fields[0].element, "<colorRed type=\"Integer\" minimum=\"0\" maximum=\"65535\"/>");
  EXPECT_EQ(fields[0].bytes, bytes_of(std::vector<std::uint16_t>{0, 1000}));
}

TEST(E57WriterPhases, CoordinatesAsFloat64) {
  const PointCloud cloud = points({{1.5, -2, 3}, {4, 5, 6.25}});
  const WriteOptions options;
  std::vector<std::string> notes;
  E57Writer e57(kPath, cloud, options, notes);
  const std::vector<OutField> fields = e57.coordinate_fields({1, 0});  // in the order of the indices
  ASSERT_EQ(fields.size(), 3u);
  EXPECT_EQ(fields[0].element, "<cartesianX type=\"Float\" precision=\"double\"/>");
  EXPECT_EQ(fields[2].element, "<cartesianZ type=\"Float\" precision=\"double\"/>");
  EXPECT_EQ(fields[0].bytes, bytes_of(std::vector<double>{4, 1.5}));
  EXPECT_EQ(fields[1].bytes, bytes_of(std::vector<double>{5, -2}));
  EXPECT_EQ(fields[2].bytes, bytes_of(std::vector<double>{6.25, 3}));
}

TEST(E57WriterPhases, CoordinatesAsBitPackedScaledIntegers) {
  const PointCloud cloud = points({{1.0, 0, 0}, {2.5, 0, 0}});
  WriteOptions options;
  options.e57_scale = 0.5;
  std::vector<std::string> notes;
  E57Writer e57(kPath, cloud, options, notes);
  const std::vector<OutField> fields = e57.coordinate_fields({0, 1});
  // x: steps 2 and 5, stored as 0 and 3 above the minimum in 2 bits each: 0b1100.
  EXPECT_EQ(fields[0].element, "<cartesianX type=\"ScaledInteger\" minimum=\"2\" maximum=\"5\" scale=\"0.5\" offset=\"0\"/>");
  EXPECT_EQ(fields[0].bytes, (std::vector<unsigned char>{0b1100}));
  // y: all 0, a constant that takes no bits.
  EXPECT_EQ(fields[1].element, "<cartesianY type=\"ScaledInteger\" minimum=\"0\" maximum=\"0\" scale=\"0.5\" offset=\"0\"/>");
  EXPECT_TRUE(fields[1].bytes.empty());
  // A coordinate past 64 bits of steps is refused, naming the point.
  const PointCloud far = points({{0, 0, 0}, {0, 1e19, 0}});
  E57Writer too_far(kPath, far, options, notes);
  expect_error<UsageError>([&] { (void)too_far.coordinate_fields({0, 1}); }, "point 1: coordinate 1e+19 does not fit");
}

TEST(E57WriterPhases, ColoursAsBytesClampedToTheUnitRange) {
  PointCloud cloud = points({{0, 0, 0}, {1, 0, 0}});
  const WriteOptions options;
  std::vector<std::string> notes;
  {
    E57Writer e57(kPath, cloud, options, notes);
    EXPECT_TRUE(e57.color_fields({0, 1}).empty());
  }
  cloud.colors = {Vector3f(1.0f, 0.0f, 0.5f), Vector3f(2.0f, -1.0f, 0.25f)};
  E57Writer e57(kPath, cloud, options, notes);
  const std::vector<OutField> fields = e57.color_fields({0, 1});
  ASSERT_EQ(fields.size(), 3u);
  EXPECT_EQ(fields[0].element, "<colorRed type=\"Integer\" minimum=\"0\" maximum=\"255\"/>");
  EXPECT_EQ(fields[0].bytes, (std::vector<unsigned char>{255, 255}));
  EXPECT_EQ(fields[1].bytes, (std::vector<unsigned char>{0, 0}));
  EXPECT_EQ(fields[2].bytes, (std::vector<unsigned char>{128, 64}));  // 127.5 and 63.75 rounded
}

TEST(E57WriterPhases, NormalsAsFloat32InTheirNamespace) {
  PointCloud cloud = points({{0, 0, 0}, {1, 0, 0}});
  const WriteOptions options;
  std::vector<std::string> notes;
  {
    E57Writer e57(kPath, cloud, options, notes);
    EXPECT_TRUE(e57.normal_fields({0, 1}).empty());
    EXPECT_FALSE(e57.any_normals);
  }
  cloud.normals = {{0, 0, 1}, {0.6, 0.8, 0}};
  E57Writer e57(kPath, cloud, options, notes);
  const std::vector<OutField> fields = e57.normal_fields({0, 1});
  EXPECT_TRUE(e57.any_normals);
  ASSERT_EQ(fields.size(), 3u);
  EXPECT_EQ(fields[1].element, "<nor:normalY type=\"Float\" precision=\"single\"/>");
  EXPECT_EQ(fields[0].bytes, bytes_of(std::vector<float>{0.0f, 0.6f}));
  EXPECT_EQ(fields[1].bytes, bytes_of(std::vector<float>{0.0f, 0.8f}));
}

TEST(E57WriterPhases, ExtraFieldsByKindAndName) {
  PointCloud cloud = points({{0, 0, 0}, {1, 0, 0}});
  add_field(cloud, "scan", {0, 0});
  add_field(cloud, "intensity", {10, 30});
  add_field(cloud, "rowIndex", {7, 4}, ScalarType::Int32);
  add_field(cloud, "label", {0.5, 1.5}, ScalarType::Float32);
  add_field(cloud, "1abc", {1, 2});
  const WriteOptions options;
  std::vector<std::string> notes;
  E57Writer e57(kPath, cloud, options, notes);
  e57.group_scans();
  e57.set_intensity_limits();
  const std::vector<OutField> fields = e57.extra_fields(0, {0, 1});
  ASSERT_EQ(fields.size(), 3u);  // no scan (it is the grouping), no 1abc (not an XML name)
  EXPECT_EQ(fields[0].element, "<intensity type=\"Float\" precision=\"double\"/>");
  EXPECT_EQ(fields[0].bytes, bytes_of(std::vector<double>{10.0, 30.0}));  // the values, within the limits [10, 30]
  // An E57 point field keeps its name: 7 and 4, as 3 and 0 above the minimum in 2 bits: 0b0011.
  EXPECT_EQ(fields[1].element, "<rowIndex type=\"Integer\" minimum=\"4\" maximum=\"7\"/>");
  EXPECT_EQ(fields[1].bytes, (std::vector<unsigned char>{0b0011}));
  EXPECT_EQ(fields[2].element, "<pointsurf:label type=\"Float\" precision=\"single\"/>");
  EXPECT_EQ(fields[2].bytes, bytes_of(std::vector<float>{0.5f, 1.5f}));
  EXPECT_TRUE(e57.any_extension);
  EXPECT_EQ(e57.skipped, (std::vector<std::string>{"1abc"}));
  // A field left out is named once, in the first scan only.
  (void)e57.extra_fields(1, {1});
  EXPECT_EQ(e57.skipped, (std::vector<std::string>{"1abc"}));
  e57.note_skipped_fields();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0], "field(s) 1abc not written: an E57 field name must be an XML name");
}

TEST(E57WriterPhases, ScanIsOneSectionOfOnePacketAndItsStructure) {
  const PointCloud cloud = points({{1, 2, 3}, {4, 5, 6}, {7, 8, 9}});
  WriteOptions options;
  options.scan_poses.resize(1);
  options.scan_poses[0].name = "north";
  options.scan_poses[0].translation = Vector3d(10, 20, 30);
  std::vector<std::string> notes;
  E57Writer e57(kPath, cloud, options, notes);
  e57.group_scans();
  e57.set_intensity_limits();
  e57.start_file();
  ASSERT_EQ(e57.writer.size(), io::detail::kE57HeaderSize);
  e57.write_scan(0, {0, 1, 2});
  const std::string_view bytes = e57.writer.bytes();
  // The section header right after the file header, then one data packet: type, flags, length
  // - 1, 3 bytestreams of 24 bytes each (x, y, z of 3 points as float64).
  const std::size_t section = io::detail::kE57HeaderSize, packet = section + io::detail::kSectionHeaderSize;
  const std::size_t packet_size = 6 + 2 * 3 + 3 * 24;
  ASSERT_EQ(bytes.size(), packet + packet_size);
  EXPECT_EQ(bytes[section], io::detail::kCompressedVectorSection);
  EXPECT_EQ(read_at<std::uint64_t>(bytes, section + 8), io::detail::kSectionHeaderSize + packet_size);
  EXPECT_EQ(read_at<std::uint64_t>(bytes, section + 16), io::detail::e57_physical(packet));
  EXPECT_EQ(bytes[packet], io::detail::kDataPacket);
  EXPECT_EQ(read_at<std::uint16_t>(bytes, packet + 2), packet_size - 1);
  EXPECT_EQ(read_at<std::uint16_t>(bytes, packet + 4), 3);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(read_at<std::uint16_t>(bytes, packet + 6 + 2 * k), 24);
  EXPECT_EQ(read_at<double>(bytes, packet + 12), 1.0);
  EXPECT_EQ(read_at<double>(bytes, packet + 12 + 24 + 16), 8.0);  // y of the third point
  // Its structure names the scan, its pose and where its points are.
  const std::string& xml = e57.scans_xml;
  EXPECT_TRUE(contains(xml, "<name type=\"String\"><![CDATA[north]]></name>")) << xml;
  EXPECT_TRUE(contains(xml, "<translation type=\"Structure\"><x type=\"Float\">10</x><y type=\"Float\">20</y><z type=\"Float\">30</z>")) << xml;
  EXPECT_TRUE(contains(xml, fmt::format("fileOffset=\"{}\" recordCount=\"3\"", io::detail::e57_physical(section)))) << xml;
  EXPECT_TRUE(contains(xml, "          <cartesianZ type=\"Float\" precision=\"double\"/>\n")) << xml;
  EXPECT_FALSE(contains(xml, "intensityLimits"));
  EXPECT_FALSE(contains(xml, "colorLimits"));
}

TEST(E57WriterPhases, XmlDeclaresOnlyTheNamespacesUsed) {
  PointCloud cloud = points({{0, 0, 0}});
  cloud.crs.wkt = "LOCAL_CS[\"here\"]";
  const WriteOptions options;
  std::vector<std::string> notes;
  E57Writer e57(kPath, cloud, options, notes);
  e57.start_file();
  e57.scans_xml = "    <vectorChild/>\n";
  e57.compose_xml();
  EXPECT_TRUE(contains(e57.xml, "<e57Root type=\"Structure\" xmlns=\"http://www.astm.org/COMMIT/E57/2010-e57-v1.0\">")) << e57.xml;
  EXPECT_TRUE(contains(e57.xml, "<data3D type=\"Vector\" allowHeterogeneousChildren=\"1\">\n    <vectorChild/>\n  </data3D>"));
  EXPECT_TRUE(contains(e57.xml, "<coordinateMetadata type=\"String\"><![CDATA[LOCAL_CS[\"here\"]]]></coordinateMetadata>"));
  e57.any_normals = e57.any_extension = true;
  e57.compose_xml();
  EXPECT_TRUE(contains(e57.xml, " xmlns:nor=\"http://www.libe57.org/E57_NOR_surface_normals.txt\""));
  EXPECT_TRUE(contains(e57.xml, " xmlns:pointsurf=\"https://pointsurf.org/e57-fields\""));
}

TEST(E57WriterPhases, HeaderPointsAtTheXmlAndCountsWholePages) {
  const PointCloud cloud = points({{0, 0, 0}});
  const WriteOptions options;
  std::vector<std::string> notes;
  E57Writer e57(kPath, cloud, options, notes);
  e57.start_file();
  e57.xml = std::string(2000, 'x');  // with the 48-byte header: 2048 logical bytes, 3 pages of 1020
  e57.append_xml_and_header();
  const std::string_view bytes = e57.writer.bytes();
  EXPECT_EQ(e57.xml_logical, 48u);
  EXPECT_EQ(bytes.substr(0, 8), "ASTM-E57");
  EXPECT_EQ(read_at<std::uint32_t>(bytes, 8), 1u);
  EXPECT_EQ(read_at<std::uint32_t>(bytes, 12), 0u);
  EXPECT_EQ(read_at<std::uint64_t>(bytes, 16), 3u * 1024u);
  EXPECT_EQ(read_at<std::uint64_t>(bytes, 24), 48u);  // still on the first page: physical = logical
  EXPECT_EQ(read_at<std::uint64_t>(bytes, 32), 2000u);
  EXPECT_EQ(read_at<std::uint64_t>(bytes, 40), 1024u);
  EXPECT_EQ(bytes.substr(48), e57.xml);
}

TEST(E57WriterPhases, SavedFileIsWholeCheckedPages) {
  const PointCloud cloud = points({{1, 2, 3}, {4, 5, 6}});
  const WriteOptions options;
  std::vector<std::string> notes;
  const std::filesystem::path path = test::temp_dir("e57_writer_phases") / "two.e57";
  E57Writer e57(path, cloud, options, notes);
  e57.group_scans();
  e57.set_intensity_limits();
  e57.start_file();
  for (const auto& [scan, indices] : e57.groups) e57.write_scan(scan, indices);
  e57.compose_xml();
  e57.append_xml_and_header();
  e57.save();
  const std::string file = test::read_bytes(path);
  ASSERT_EQ(file.size() % 1024, 0u);
  const io::detail::E57PagedReader reader(file, "two.e57");  // checks the header and every page's CRC
  EXPECT_EQ(reader.header().file_physical_length, file.size());
  EXPECT_EQ(reader.header().xml_logical_length, e57.xml.size());
  std::string xml(e57.xml.size(), '\0');
  reader.read(e57.xml_logical, xml.size(), xml.data(), "xml");
  EXPECT_EQ(xml, e57.xml);
}

}  // namespace
}  // namespace pointsurf
