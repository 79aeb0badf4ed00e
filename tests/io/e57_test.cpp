// SPDX-License-Identifier: GPL-3.0-or-later
// E57: the reference files of libE57 and libE57Format read to the points they state, files built
// here byte by byte (independent bit packing and CRC-32C) exercise every field kind, and
// corrupted files give named InputErrors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "support/cli_run.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::expect_error;
using test::write_bytes;


// CRC-32C bit by bit (the library uses a table or SSE4.2).
std::uint32_t crc32c_bitwise(const char* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= static_cast<unsigned char>(p[i]);
    for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
  }
  return ~c;
}

// Physical file of logical bytes: 1020 per page, then the CRC big endian.
std::string paged(const std::string& logical) {
  std::string out;
  for (std::size_t at = 0; at == 0 || at < logical.size(); at += 1020) {
    std::string page = logical.substr(std::min(at, logical.size()), 1020);
    page.resize(1020, '\0');
    const std::uint32_t crc = crc32c_bitwise(page.data(), 1020);
    for (int b = 3; b >= 0; --b) page.push_back(static_cast<char>(crc >> (8 * b)));
    out += page;
  }
  return out;
}
std::string unpaged(const std::string& physical) {
  std::string out;
  for (std::size_t at = 0; at < physical.size(); at += 1024) out += physical.substr(at, 1020);
  return out;
}
std::uint64_t physical_of(std::uint64_t logical) { return logical / 1020 * 1024 + logical % 1020; }

template <typename T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <typename T>
void put_at(std::string& s, std::size_t at, T v) {
  std::memcpy(s.data() + at, &v, sizeof(T));
}

// Bit packing one bit at a time, least significant first.
std::string pack(const std::vector<std::uint64_t>& values, unsigned bits) {
  std::string out((values.size() * bits + 7) / 8, '\0');
  std::size_t bit = 0;
  for (std::uint64_t v : values)
    for (unsigned b = 0; b < bits; ++b, ++bit)
      if ((v >> b) & 1) out[bit / 8] = static_cast<char>(out[bit / 8] | (1 << (bit % 8)));
  return out;
}
template <typename T>
std::string raw_floats(const std::vector<double>& values) {
  std::string out;
  for (double v : values) put<T>(out, static_cast<T>(v));
  return out;
}

// An E57 file built by hand: each scan gives its XML (with FILEOFFSET for the section's
// offset) and its bytestreams, split over `packets` data packets, with an index packet and an
// empty packet in between to be skipped.
struct HandScan {
  std::string xml;
  std::vector<std::string> streams;
  int packets = 1;
};

std::string build_e57(const std::vector<HandScan>& scans, const std::string& extra_root_xml = {}) {
  std::string logical(48, '\0');
  std::string data3d;
  for (const HandScan& scan : scans) {
    while (logical.size() % 4) logical.push_back('\0');
    const std::size_t start = logical.size();
    logical.append(32, '\0');
    for (int p = 0; p < scan.packets; ++p) {
      std::string packet;
      put<std::uint8_t>(packet, 1);
      put<std::uint8_t>(packet, 0);
      put<std::uint16_t>(packet, 0);
      put<std::uint16_t>(packet, static_cast<std::uint16_t>(scan.streams.size()));
      std::string body;
      for (const std::string& s : scan.streams) {
        const std::size_t from = s.size() * p / scan.packets, to = s.size() * (p + 1) / scan.packets;
        put<std::uint16_t>(packet, static_cast<std::uint16_t>(to - from));
        body += s.substr(from, to - from);
      }
      packet += body;
      while (packet.size() % 4) packet.push_back('\0');
      put_at<std::uint16_t>(packet, 2, static_cast<std::uint16_t>(packet.size() - 1));
      logical += packet;
      if (p == 0) {
        std::string index(16, '\0');  // an index packet: type 0, 16 bytes, no entries
        put_at<std::uint16_t>(index, 2, 15);
        std::string empty(8, '\0');  // an empty packet: type 2
        empty[0] = 2;
        put_at<std::uint16_t>(empty, 2, 7);
        logical += index + empty;
      }
    }
    logical[start] = 1;
    put_at<std::uint64_t>(logical, start + 8, logical.size() - start);
    put_at<std::uint64_t>(logical, start + 16, physical_of(start + 32));
    std::string xml = scan.xml;
    xml.replace(xml.find("FILEOFFSET"), 10, std::to_string(physical_of(start)));
    data3d += xml;
  }
  const std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<e57Root type=\"Structure\" xmlns=\"http://www.astm.org/COMMIT/E57/2010-e57-v1.0\">"
                          "<data3D type=\"Vector\">" + data3d + "</data3D>" + extra_root_xml + "</e57Root>";
  while (logical.size() % 4) logical.push_back('\0');
  const std::size_t xml_at = logical.size();
  logical += xml;
  const std::size_t pages = (logical.size() + 1019) / 1020;
  std::memcpy(logical.data(), "ASTM-E57", 8);
  put_at<std::uint32_t>(logical, 8, 1);
  put_at<std::uint64_t>(logical, 16, pages * 1024);
  put_at<std::uint64_t>(logical, 24, physical_of(xml_at));
  put_at<std::uint64_t>(logical, 32, xml.size());
  put_at<std::uint64_t>(logical, 40, 1024);
  return paged(logical);
}

std::string scan_xml(const std::string& name, std::size_t records, const std::string& prototype, const std::string& extra = {}) {
  return fmt::format("<vectorChild type=\"Structure\"><name type=\"String\"><![CDATA[{}]]></name>{}"
                     "<points type=\"CompressedVector\" fileOffset=\"FILEOFFSET\" recordCount=\"{}\"><prototype type=\"Structure\">{}</prototype>"
                     "<codecs type=\"Vector\"/></points></vectorChild>",
                     name, extra, records, prototype);
}

CloudReadResult read_bytes_as_e57(const std::filesystem::path& dir, const std::string& bytes, const ReadOptions& options = {}) {
  return read_point_cloud(write_bytes(dir / "hand.e57", bytes), options);
}

TEST(E57, ReferenceBunnyReadsToTheCoordinatesItStates) {
  const CloudReadResult r = read_point_cloud(test::test_data_path("bunnyDouble.e57"));
  EXPECT_EQ(r.format, "e57");
  ASSERT_EQ(r.cloud.size(), 30571u);  // recordCount in its XML; no point is flagged invalid
  EXPECT_TRUE(r.cloud.fields.empty()) << "cartesianInvalidState is consumed, not kept";
  // The values an independent decoder (Python, walking the packets) gave.
  EXPECT_EQ(r.cloud.positions[0], Vector3d(-0.07063, 0.04015, 0.0012259999999999999));
  EXPECT_EQ(r.cloud.positions[1], Vector3d(-0.070891, 0.040326, 0.002828));
  EXPECT_EQ(r.cloud.positions[12345], Vector3d(-0.022704, 0.065145, 0.045659));
  EXPECT_EQ(r.cloud.positions[30570], Vector3d(-0.037829, 0.12794, 0.004474));
  // cartesianBounds in its XML.
  const BoundingBox box = bounding_box(r.cloud.positions);
  EXPECT_EQ(box.min, Vector3d(-9.4688999999999995e-002, 4.0010999999999998e-002, -6.1872999999999997e-002));
  EXPECT_EQ(box.max, Vector3d(6.1008999999999994e-002, 1.8732099999999999e-001, 5.8798999999999997e-002));
  ASSERT_EQ(r.scans.size(), 1u);
  EXPECT_EQ(r.scans[0].name, "bunny");
  EXPECT_EQ(r.scans[0].points, 30571u);
}

TEST(E57, ReferenceColouredCubeReadsItsColours) {
  const CloudReadResult r = read_point_cloud(test::test_data_path("ColouredCubeFloat.e57"));
  ASSERT_EQ(r.cloud.size(), 7680u);
  ASSERT_TRUE(r.cloud.has_colors());
  EXPECT_EQ(r.cloud.positions[0], Vector3d(-0.5, -0.4990559220314026, 0.07136291265487671));
  EXPECT_EQ(r.cloud.colors[0], Vector3f(0, 0, 1));  // 0 0 255 with colorLimits 0..255
  EXPECT_EQ(r.cloud.positions[7679], Vector3d(0.16827905178070068, -0.00394439697265625, 0.5));
  EXPECT_EQ(r.cloud.colors[7679], Vector3f(1, 0, 0));
  for (const Vector3d& p : r.cloud.positions) EXPECT_LE(p.cwiseAbs().maxCoeff(), 0.5);
}

TEST(E57, BadChecksumIsRefusedNamingThePage) {
  expect_error<InputError>([] { read_point_cloud(test::test_data_path("bad-crc.e57")); }, "bad-crc.e57: page 0 (bytes 0..1023): CRC-32C checksum mismatch");
}

TEST(E57, CliRefusesBadChecksumWithExitCode2AndNoOutput) {
  const auto dir = test::temp_dir("e57_cli_crc");
  const test::RunResult r = test::run_cli(fmt::format("convert {} {}", (test::test_data_path("bad-crc.e57")).string(), (dir / "out.ply").string()), dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(test::contains(r.err, "page 0")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.ply"));
}

// Two scans in their own frames, with colours, intensity, normals and two more fields.
PointCloud two_scans() {
  PointCloud c;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  ScalarField& scan = c.fields.add("scan", 0, ScalarType::UInt16);
  ScalarField& label = c.fields.add("label", 0, ScalarType::Int32);
  ScalarField& deviation = c.fields.add("deviation", 0, ScalarType::Float64);
  ScalarField& intensity = c.fields.add("intensity", 0, ScalarType::Float32);
  for (int i = 0; i < 3000; ++i) {
    c.positions.emplace_back(u(rng), u(rng), u(rng));
    c.normals.push_back(Vector3d(u(rng), u(rng), u(rng) + 5).normalized());
    c.colors.emplace_back(float(i % 256) / 255.0f, float((7 * i) % 256) / 255.0f, float((13 * i) % 256) / 255.0f);
    scan.values.push_back(i < 1200 ? 0 : 1);
    label.values.push_back((i * 37) % 1001 - 500);
    deviation.values.push_back(u(rng) * 1e-3);
    intensity.values.push_back(float(u(rng) * 0.25 + 0.5));
  }
  return c;
}

std::vector<ScanPose> two_poses() {
  std::vector<ScanPose> poses(2);
  poses[0].name = "north";
  poses[0].rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vector3d(1, 2, 3).normalized()));
  poses[0].translation = Vector3d(100.5, -20.25, 3.0);
  poses[1].name = "south";
  poses[1].rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-1.2, Vector3d(0, 0, 1)));
  poses[1].translation = Vector3d(-7.0, 42.0, 0.5);
  return poses;
}

TEST(E57, TwoScansWithPosesRoundTripAppliedOrKeptApart) {
  const auto dir = test::temp_dir("e57_two_scans");
  const PointCloud c = two_scans();
  WriteOptions options;
  options.scan_poses = two_poses();
  write_point_cloud(dir / "two.e57", c, options);

  ReadOptions apart;
  apart.apply_poses = false;
  const CloudReadResult local = read_point_cloud(dir / "two.e57", apart);
  ASSERT_EQ(local.cloud.size(), c.size());
  EXPECT_EQ(local.cloud.positions, c.positions);  // float64: bit-identical
  ASSERT_EQ(local.scans.size(), 2u);
  EXPECT_EQ(local.scans[0].name, "north");
  EXPECT_EQ(local.scans[1].points, 1800u);
  for (int s = 0; s < 2; ++s) {
    EXPECT_LT((local.scans[s].translation - options.scan_poses[s].translation).norm(), 1e-15);
    EXPECT_LT(local.scans[s].rotation.angularDistance(options.scan_poses[s].rotation), 1e-12);
  }
  EXPECT_EQ(local.cloud.fields.find("scan")->values, c.fields.find("scan")->values);
  EXPECT_EQ(local.cloud.fields.find("label")->values, c.fields.find("label")->values);
  EXPECT_EQ(local.cloud.fields.find("label")->type, ScalarType::Int16);  // range -500..500
  EXPECT_EQ(local.cloud.fields.find("deviation")->values, c.fields.find("deviation")->values);
  EXPECT_EQ(local.cloud.fields.find("intensity")->values, c.fields.find("intensity")->values);  // in [0, 1]: limits 0..1
  EXPECT_EQ(local.cloud.colors, c.colors);
  for (std::size_t i = 0; i < c.size(); ++i) EXPECT_LT((local.cloud.normals[i] - c.normals[i]).norm(), 1e-7);

  const CloudReadResult world = read_point_cloud(dir / "two.e57");
  ASSERT_EQ(world.cloud.size(), c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    const ScanPose& pose = options.scan_poses[i < 1200 ? 0 : 1];
    EXPECT_LT((world.cloud.positions[i] - (pose.rotation * c.positions[i] + pose.translation)).norm(), 1e-12);
  }
  // Written again from world coordinates: identity poses, the same points.
  write_point_cloud(dir / "world.e57", world.cloud);
  const CloudReadResult again = read_point_cloud(dir / "world.e57", apart);
  EXPECT_EQ(again.cloud.positions, world.cloud.positions);
  EXPECT_EQ(again.scans[1].translation, Vector3d::Zero());
}

TEST(E57, ScaledIntegerCoordinatesKeepGeoreferencedPointsToHalfTheStep) {
  const auto dir = test::temp_dir("e57_scaled");
  PointCloud c;
  for (int i = 0; i < 1000; ++i) c.positions.emplace_back(6500000.0 + i * 0.01237, 4100000.0 - i * 0.003, 120.0 + std::sin(i) * 5);
  WriteOptions options;
  options.e57_scale = 1e-4;
  write_point_cloud(dir / "geo.e57", c, options);
  const CloudReadResult r = read_point_cloud(dir / "geo.e57");
  ASSERT_EQ(r.cloud.size(), c.size());
  for (std::size_t i = 0; i < c.size(); ++i) EXPECT_LE((r.cloud.positions[i] - c.positions[i]).cwiseAbs().maxCoeff(), 0.5e-4 + 1e-9);
  // Smaller than float64 coordinates: 3 x ceil(log2(range / step)) bits per point.
  EXPECT_LT(std::filesystem::file_size(dir / "geo.e57"), std::size_t{1000} * 24 / 2);
}

TEST(E57, HandBuiltSphericalScanWithInvalidPointsAndOddBitWidths) {
  const auto dir = test::temp_dir("e57_spherical");
  // 5 points: range as a 13-bit scaled integer, azimuth and elevation as float32, a 2-bit
  // sphericalInvalidState (point 3 invalid), 3-bit intensity 0..7 with limits 0..7.
  const std::vector<std::uint64_t> range_raw = {1000, 2000, 4095, 8191, 0};  // scale 1e-3, offset 1: ranges 2, 3, 5.095, 9.191, 1
  const std::vector<double> azimuth = {0.0, M_PI / 2, M_PI, 0.5, -M_PI / 2};
  const std::vector<double> elevation = {0.0, 0.0, M_PI / 4, 0.2, M_PI / 2};
  const std::vector<std::uint64_t> state = {0, 0, 0, 2, 0};
  const std::vector<std::uint64_t> intensity = {0, 7, 3, 5, 6};
  HandScan scan;
  scan.xml = scan_xml("sphere", 5,
                      "<sphericalRange type=\"ScaledInteger\" minimum=\"0\" maximum=\"8191\" scale=\"1e-3\" offset=\"1\"/>"
                      "<sphericalAzimuth type=\"Float\" precision=\"single\"/><sphericalElevation type=\"Float\" precision=\"single\"/>"
                      "<sphericalInvalidState type=\"Integer\" minimum=\"0\" maximum=\"2\"/>"
                      "<intensity type=\"Integer\" minimum=\"0\" maximum=\"7\"/>",
                      "<pose type=\"Structure\"><translation type=\"Structure\"><z type=\"Float\">10</z></translation></pose>");
  scan.streams = {pack(range_raw, 13), raw_floats<float>(azimuth), raw_floats<float>(elevation), pack(state, 2), pack(intensity, 3)};
  scan.packets = 3;
  const CloudReadResult r = read_bytes_as_e57(dir, build_e57({scan}, "<images2D type=\"Vector\"><vectorChild type=\"Structure\"/></images2D>"));
  ASSERT_EQ(r.cloud.size(), 4u);
  auto expected = [&](int i) {
    const double rr = range_raw[i] * 1e-3 + 1.0, az = float(azimuth[i]), el = float(elevation[i]);
    return Vector3d(rr * std::cos(el) * std::cos(az), rr * std::cos(el) * std::sin(az), rr * std::sin(el) + 10.0);
  };
  const int kept[4] = {0, 1, 2, 4};
  for (int k = 0; k < 4; ++k) EXPECT_LT((r.cloud.positions[k] - expected(kept[k])).norm(), 1e-12) << k;
  const ScalarField* i = r.cloud.fields.find("intensity");
  ASSERT_NE(i, nullptr);
  EXPECT_EQ(i->values, (std::vector<double>{0, 7, 3, 6}));  // the stored values: intensityLimits only give their range
  EXPECT_EQ(i->type, ScalarType::UInt8);
  EXPECT_FALSE(r.cloud.fields.contains("sphericalInvalidState"));
  bool noted_invalid = false, noted_images = false;
  for (const std::string& w : r.warnings) {
    noted_invalid |= test::contains(w, "1 point(s) flagged invalid");
    noted_images |= test::contains(w, "1 image(s) in /images2D skipped");
  }
  EXPECT_TRUE(noted_invalid);
  EXPECT_TRUE(noted_images);
}

TEST(E57, WideIntegersAndTimeStampsAreKeptAsFields) {
  const auto dir = test::temp_dir("e57_wide");
  const std::vector<std::uint64_t> wide = {0, (1ULL << 62) + 12345, (1ULL << 63) - 1, 77};  // 63-bit values
  const std::vector<std::uint64_t> row = {3, 1, 4, 1};
  HandScan scan;
  scan.xml = scan_xml("s", 4,
                      "<cartesianX type=\"Float\"/><cartesianY type=\"Float\"/><cartesianZ type=\"Float\"/>"
                      "<rowIndex type=\"Integer\" minimum=\"-5\" maximum=\"58\"/>"
                      "<pointsurf:wide type=\"Integer\" minimum=\"0\" maximum=\"9223372036854775807\"/>");
  std::vector<std::uint64_t> row_raw;
  for (std::uint64_t v : row) row_raw.push_back(v + 5);
  scan.streams = {raw_floats<double>({1, 2, 3, 4}), raw_floats<double>({0, 0, 0, 0}), raw_floats<double>({-1, -2, -3, -4}), pack(row_raw, 6),
                  pack(wide, 63)};
  const CloudReadResult r = read_bytes_as_e57(dir, build_e57({scan}));
  ASSERT_EQ(r.cloud.size(), 4u);
  EXPECT_EQ(r.cloud.fields.find("rowIndex")->values, std::vector<double>({3, 1, 4, 1}));
  EXPECT_EQ(r.cloud.fields.find("rowIndex")->type, ScalarType::Int8);
  EXPECT_EQ(r.cloud.fields.find("wide")->values[1], double((1ULL << 62) + 12345));
  EXPECT_EQ(r.cloud.positions[3], Vector3d(4, 0, -4));
}

// A valid two-scan file of our own, for the corruption tests.
std::string valid_file(const std::filesystem::path& dir) {
  PointCloud c = two_scans();
  WriteOptions options;
  options.scan_poses = two_poses();
  write_point_cloud(dir / "valid.e57", c, options);
  return test::read_bytes(dir / "valid.e57");
}

TEST(E57, CorruptedFilesGiveNamedInputErrors) {
  const auto dir = test::temp_dir("e57_corrupt");
  const std::string good = valid_file(dir);
  ASSERT_GT(good.size(), 4 * 1024u);
  // A truncated file (a whole page missing, or a partial page).
  expect_error<InputError>([&] { read_bytes_as_e57(dir, good.substr(0, good.size() - 1024)); }, "hand.e57: header: file length");
  // A flipped bit in a data page.
  std::string flipped = good;
  flipped[2 * 1024 + 100] ^= 0x10;
  expect_error<InputError>([&] { read_bytes_as_e57(dir, flipped); }, "hand.e57: page 2 (bytes 2048..3071): CRC-32C checksum mismatch");
  // Section length out of range (checksums made valid again, so the section reader sees it).
  std::string logical = unpaged(good);
  std::string bad_section = logical;
  const std::size_t section = 48;  // the first section follows the header
  put_at<std::uint64_t>(bad_section, section + 8, std::uint64_t{1} << 40);
  expect_error<InputError>([&] { read_bytes_as_e57(dir, paged(bad_section)); }, "scan 0 (north) section at byte 48: section length 1099511627776 out of range");
  // A section id that is not a compressed vector.
  std::string bad_id = logical;
  bad_id[section] = 0;
  expect_error<InputError>([&] { read_bytes_as_e57(dir, paged(bad_id)); }, "section id 0, expected 1");
  // A packet length past the section end.
  std::string bad_packet = logical;
  put_at<std::uint16_t>(bad_packet, section + 32 + 2, 0xFFFE);
  expect_error<InputError>([&] { read_bytes_as_e57(dir, paged(bad_packet)); }, "packet 0 at logical offset 80: packet length 65535 is not a multiple of 4");
  // Broken XML.
  const std::size_t xml_at = logical.find("<?xml");
  std::string bad_xml = logical;
  bad_xml.replace(bad_xml.find("</data3D>", xml_at), 9, "</dataXD>");
  expect_error<InputError>([&] { read_bytes_as_e57(dir, paged(bad_xml)); }, "hand.e57: XML section: ");
  // A record count beyond what the section holds.
  std::string bad_count = logical;
  const std::size_t rc = bad_count.find("recordCount=\"1200\"", xml_at);
  ASSERT_NE(rc, std::string::npos);
  bad_count.replace(rc, 18, "recordCount=\"9999\"");
  expect_error<InputError>([&] { read_bytes_as_e57(dir, paged(bad_count)); }, "9999 records of");
  // Many records of constant fields: no bytes, but bounded (the file is made 2.2 MB, by XML
  // blanks, so that the bound by file size does not come first).
  HandScan constant;
  constant.xml = scan_xml("c", 17000000,
                          "<cartesianX type=\"Integer\" minimum=\"1\" maximum=\"1\"/><cartesianY type=\"Integer\" minimum=\"2\" maximum=\"2\"/>"
                          "<cartesianZ type=\"Integer\" minimum=\"3\" maximum=\"3\"/>");
  constant.streams = {"", "", ""};
  expect_error<InputError>([&] { read_bytes_as_e57(dir, build_e57({constant}, std::string(2200000, ' '))); },
                           "recordCount 17000000 of points whose every field is constant");
  // Not E57 at all, and an empty file.
  expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "short.e57", "ASTM-E57")); }, "short.e57: not an E57 file");
}

// Random corruption with valid checksums: every outcome is points or an InputError, never a
// crash or a hang (run under AddressSanitizer by ./pointsurf.sh test-sanitize).
TEST(E57, RandomCorruptionGivesPointsOrInputErrors) {
  const auto dir = test::temp_dir("e57_random");
  const std::string logical = unpaged(valid_file(dir));
  std::mt19937 rng(18);
  int errors = 0, reads = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string bytes = logical;
    const int flips = 1 + trial % 4;
    for (int f = 0; f < flips; ++f) {
      // Half the flips hit the header, the section headers, the first packet or the XML.
      std::size_t at = rng() % bytes.size();
      if (trial % 2 == 0) {
        const std::size_t xml = bytes.find("<?xml");
        const std::size_t pick = rng() % 4;
        at = pick == 0 ? rng() % 48 : pick == 1 ? 48 + rng() % 80 : xml + rng() % (bytes.size() - xml);
      }
      bytes[at] = static_cast<char>(bytes[at] ^ (1 << (rng() % 8)));
    }
    try {
      read_bytes_as_e57(dir, paged(bytes));
      ++reads;
    } catch (const InputError&) {
      ++errors;
    }
  }
  EXPECT_EQ(errors + reads, 300);
  EXPECT_GT(errors, 0);
}

TEST(E57, CliKeepsPosesApartThroughConvertAndInfoShowsThem) {
  const auto dir = test::temp_dir("e57_cli_poses");
  WriteOptions options;
  options.scan_poses = two_poses();
  write_point_cloud(dir / "two.e57", two_scans(), options);
  const test::RunResult kept = test::run_cli(fmt::format("convert {} {} --keep-poses", (dir / "two.e57").string(), (dir / "kept.e57").string()), dir);
  ASSERT_EQ(kept.exit_code, 0) << kept.err;
  const CloudReadResult before = read_point_cloud(dir / "two.e57"), after = read_point_cloud(dir / "kept.e57");
  EXPECT_EQ(after.cloud.positions, before.cloud.positions);  // the poses travelled with the scans
  const test::RunResult info = test::run_cli(fmt::format("info {}", (dir / "kept.e57").string()), dir);
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_TRUE(test::contains(info.out, "scan         south: 1800 points, pose rotation (w x y z) 0.825335615")) << info.out;
}

// Issue 28: LAS intensities 996..57345 came back from LAS -> E57 -> LAS as floats near -0.0177
// (stored normalised under intensityLimits [996, 57345], then normalised again on reading).
// E57 stores intensity as its value; a uint16 field is an Integer within intensityLimits 0..65535.
TEST(E57, LasIntensityKeepsItsValuesThroughE57AndBackToLas) {
  const auto dir = test::temp_dir("e57_las_intensity");
  PointCloud c;
  ScalarField& intensity = c.fields.add("intensity", 0, ScalarType::UInt16);
  std::mt19937 rng(28);
  std::uniform_int_distribution<int> value(996, 57345);
  for (int i = 0; i < 500; ++i) {
    c.positions.emplace_back(0.01 * i, 0.02 * (i % 7), 1.0);
    intensity.values.push_back(i == 0 ? 996 : i == 1 ? 57345 : value(rng));
  }
  write_point_cloud(dir / "in.las", c);
  const test::RunResult to_e57 = test::run_cli(fmt::format("convert {} {}", (dir / "in.las").string(), (dir / "mid.e57").string()), dir);
  ASSERT_EQ(to_e57.exit_code, 0) << to_e57.err;
  EXPECT_FALSE(test::contains(to_e57.err, "intensityLimits")) << to_e57.err;
  const std::string xml = unpaged(test::read_bytes(dir / "mid.e57"));
  EXPECT_TRUE(test::contains(xml, "<intensity type=\"Integer\" minimum=\"0\" maximum=\"65535\"/>"));
  EXPECT_TRUE(test::contains(xml, "<intensityMinimum type=\"Float\">0</intensityMinimum><intensityMaximum type=\"Float\">65535</intensityMaximum>"));
  const CloudReadResult mid = read_point_cloud(dir / "mid.e57");
  ASSERT_NE(mid.cloud.fields.find("intensity"), nullptr);
  EXPECT_EQ(mid.cloud.fields.find("intensity")->values, intensity.values);
  EXPECT_EQ(mid.cloud.fields.find("intensity")->type, ScalarType::UInt16);
  EXPECT_TRUE(mid.warnings.empty());
  const test::RunResult to_las = test::run_cli(fmt::format("convert {} {}", (dir / "mid.e57").string(), (dir / "out.las").string()), dir);
  ASSERT_EQ(to_las.exit_code, 0) << to_las.err;
  const CloudReadResult out = read_point_cloud(dir / "out.las");
  ASSERT_NE(out.cloud.fields.find("intensity"), nullptr);
  EXPECT_EQ(out.cloud.fields.find("intensity")->values, intensity.values);
  EXPECT_EQ(out.cloud.fields.find("intensity")->type, ScalarType::UInt16);  // in its LAS slot, not extra bytes
  const auto [lo, hi] = std::minmax_element(out.cloud.fields.find("intensity")->values.begin(), out.cloud.fields.find("intensity")->values.end());
  EXPECT_EQ(*lo, 996.0);
  EXPECT_EQ(*hi, 57345.0);
}

// Float intensity outside [0, 1] is stored as it is, with its own range as the limits; a file
// whose intensities all lie in [0, 1] but outside its declared limits (what pointsurf wrote
// before issue 28) is read back against those limits, with a warning.
TEST(E57, FloatIntensityIsStoredAsItsValueAndOldNormalisedFilesAreScaledBack) {
  const auto dir = test::temp_dir("e57_float_intensity");
  PointCloud c;
  c.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  c.fields.add("intensity", 0, ScalarType::Float64).values = {-2.5, 0.75, 40.0};
  write_point_cloud(dir / "f.e57", c);
  const CloudReadResult f = read_point_cloud(dir / "f.e57");
  EXPECT_EQ(f.cloud.fields.find("intensity")->values, c.fields.find("intensity")->values);
  EXPECT_TRUE(f.warnings.empty());

  HandScan scan;
  scan.xml = scan_xml("old", 3,
                      "<cartesianX type=\"Float\"/><cartesianY type=\"Float\"/><cartesianZ type=\"Float\"/><intensity type=\"Float\"/>",
                      "<intensityLimits type=\"Structure\"><intensityMinimum type=\"Float\">996</intensityMinimum>"
                      "<intensityMaximum type=\"Float\">57345</intensityMaximum></intensityLimits>");
  scan.streams = {raw_floats<double>({0, 1, 2}), raw_floats<double>({0, 0, 0}), raw_floats<double>({0, 0, 0}),
                  raw_floats<double>({0.0, 1.0, (20000.0 - 996.0) / (57345.0 - 996.0)})};
  const CloudReadResult old = read_bytes_as_e57(dir, build_e57({scan}));
  const std::vector<double>& v = old.cloud.fields.find("intensity")->values;
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0], 996.0);
  EXPECT_EQ(v[1], 57345.0);
  EXPECT_NEAR(v[2], 20000.0, 1e-9);
  ASSERT_EQ(old.warnings.size(), 1u);
  EXPECT_TRUE(test::contains(old.warnings[0], "intensity lies in [0, 1], outside its intensityLimits [996, 57345]")) << old.warnings[0];
}

// Colours that are not 8-bit (LAS's 16-bit) are written with colorLimits 0..65535, so E57 keeps them.
TEST(E57, SixteenBitColoursKeepTheirSixteenBits) {
  const auto dir = test::temp_dir("e57_colour16");
  PointCloud c;
  c.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0)};
  c.colors = {Vector3f(1000 / 65535.0f, 65535 / 65535.0f, 0.0f), Vector3f(257 / 65535.0f, 12345 / 65535.0f, 3 / 65535.0f)};
  write_point_cloud(dir / "c.e57", c);
  EXPECT_TRUE(test::contains(unpaged(test::read_bytes(dir / "c.e57")), "<colorRed type=\"Integer\" minimum=\"0\" maximum=\"65535\"/>"));
  EXPECT_EQ(read_point_cloud(dir / "c.e57").cloud.colors, c.colors);
}

// pointsurf's E57 read by another implementation: web-e57 1.2.0 from npm (the Rust e57 crate as
// WebAssembly), run by node. Skipped unless node and the package are there (./pointsurf.sh test
// installs it: `npm install --prefix build/npm web-e57@1.2.0`), or name its folder in POINTSURF_WEB_E57.
TEST(E57, AnotherImplementationReadsOurTwoScansWithPoses) {
  const char* env = std::getenv("POINTSURF_WEB_E57");
  const std::filesystem::path package =
      env ? std::filesystem::path(env) : std::filesystem::path(POINTSURF_CLI_PATH).parent_path() / "npm" / "node_modules" / "web-e57";
  if (!std::filesystem::exists(package / "e57_bg.wasm") || std::system("node --version > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "node or web-e57 missing (" << package << ")";
  const auto dir = test::temp_dir("e57_interop");
  PointCloud c = two_scans();
  c.fields = FieldSet();
  ScalarField& scan = c.fields.add("scan", c.size(), ScalarType::UInt16);
  for (std::size_t i = 0; i < c.size(); ++i) scan.values[i] = i < 1200 ? 0 : 1;
  const std::filesystem::path script = std::filesystem::path(POINTSURF_DATA_DIR).parent_path() / "tests" / "io" / "e57_interop.mjs";
  for (const bool scaled : {false, true}) {
    WriteOptions options;
    options.scan_poses = two_poses();
    if (scaled) options.e57_scale = 1e-6;
    write_point_cloud(dir / "ours.e57", c, options);
    const std::string command = fmt::format("node {} {} {} {}", script.string(), package.string(), (dir / "ours.e57").string(), (dir / "theirs.xyz").string());
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    ReadOptions columns;
    columns.columns = "x,y,z,r,g,b";
    const CloudReadResult theirs = read_point_cloud(dir / "theirs.xyz", columns);
    const CloudReadResult ours = read_point_cloud(dir / "ours.e57");
    ASSERT_EQ(theirs.cloud.size(), c.size());
    double worst = 0;
    for (std::size_t i = 0; i < c.size(); ++i) worst = std::max(worst, (theirs.cloud.positions[i] - ours.cloud.positions[i]).norm());
    EXPECT_LT(worst, 1e-12) << (scaled ? "scaled integers" : "float64");
    // web-e57 writes colours as 0..255, read back by the XYZ reader as such.
    for (std::size_t i = 0; i < c.size(); i += 97) EXPECT_NEAR(theirs.cloud.colors[i].x(), ours.cloud.colors[i].x(), 1e-6) << i;
  }
}

TEST(E57, CoordinateSystemRoundTripsThroughTheRootCoordinateMetadata) {
  const auto dir = test::temp_dir("e57_crs");
  PointCloud c = two_scans();
  c.crs.wkt = "PROJCS[\"ETRS89 / UTM zone 32N\",GEOGCS[\"ETRS89\"],AUTHORITY[\"EPSG\",\"25832\"]]";
  write_point_cloud(dir / "crs.e57", c);
  const PointCloud back = read_point_cloud(dir / "crs.e57").cloud;
  EXPECT_EQ(back.crs.wkt, c.crs.wkt);
  EXPECT_EQ(back.crs.describe(), "ETRS89 / UTM zone 32N (EPSG:25832)");
  write_point_cloud(dir / "none.e57", two_scans());
  EXPECT_TRUE(read_point_cloud(dir / "none.e57").cloud.crs.empty());
}

}  // namespace
}  // namespace pointsurf
