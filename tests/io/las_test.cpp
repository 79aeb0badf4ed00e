// SPDX-License-Identifier: GPL-3.0-or-later
// LAS: write-then-read of a georeferenced cloud, hand-built files of several versions and
// point formats, and every malformed-header path.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::expect_error;

using test::write_bytes;
using test::read_bytes;

static_assert(std::endian::native == std::endian::little, "the hand-built files below are assembled in host byte order");

using test::get;
using test::put;

// A LAS file assembled byte by byte from the public header block layout of the specification.
struct LasFile {
  int major = 1;
  int minor = 2;
  int format = 0;
  std::size_t record_length = 20;
  std::uint32_t legacy_count = 0;
  std::uint64_t count64 = 0;           // LAS 1.4 only
  std::size_t header_size = 0;         // 0: the size the version defines
  double scale[3] = {0.01, 0.01, 0.01};
  double offset[3] = {0, 0, 0};
  std::string vlrs;                    // bytes between the header and the points
  std::uint32_t vlr_count = 0;         // 0: one VLR when `vlrs` holds any
  std::string points;                  // the point records
  std::string evlrs;                   // LAS 1.4: extended VLRs after the points
  std::uint32_t evlr_count = 0;

  std::string bytes() const {
    const std::size_t size = header_size ? header_size : minor >= 4 ? 375 : minor == 3 ? 235 : 227;
    std::string h(std::max<std::size_t>(size, 227), '\0');
    std::memcpy(h.data(), "LASF", 4);
    h[24] = static_cast<char>(major);
    h[25] = static_cast<char>(minor);
    std::memcpy(h.data() + 58, "handmade", 8);
    put<std::uint16_t>(h, 94, static_cast<std::uint16_t>(size));
    put<std::uint32_t>(h, 96, static_cast<std::uint32_t>(size + vlrs.size()));
    put<std::uint32_t>(h, 100, vlr_count ? vlr_count : vlrs.empty() ? 0 : 1);
    h[104] = static_cast<char>(format);
    put<std::uint16_t>(h, 105, static_cast<std::uint16_t>(record_length));
    put<std::uint32_t>(h, 107, legacy_count);
    for (int a = 0; a < 3; ++a) {
      put<double>(h, 131 + 8 * a, scale[a]);
      put<double>(h, 155 + 8 * a, offset[a]);
    }
    if (h.size() >= 375) put<std::uint64_t>(h, 247, count64);
    if (h.size() >= 375 && evlr_count) {
      put<std::uint64_t>(h, 235, h.size() + vlrs.size() + points.size());
      put<std::uint32_t>(h, 243, evlr_count);
    }
    return h + vlrs + points + evlrs;
  }
};

// A 54-byte VLR header plus a payload, filled with bytes a reader must skip.
std::string projection_vlr() {
  std::string v(54 + 16, '\x7f');
  put<std::uint16_t>(v, 0, 0);
  std::memcpy(v.data() + 2, "LASF_Projection\0", 16);
  put<std::uint16_t>(v, 18, 34735);
  put<std::uint16_t>(v, 20, 16);
  return v;
}

// The 20-byte core of formats 0-5.
std::string legacy_record(std::size_t length, std::int32_t x, std::int32_t y, std::int32_t z, std::uint16_t intensity,
                          std::uint8_t returns_byte, std::uint8_t class_byte, std::int8_t scan_angle, std::uint8_t user_data,
                          std::uint16_t source) {
  std::string r(length, '\0');
  put(r, 0, x);
  put(r, 4, y);
  put(r, 8, z);
  put(r, 12, intensity);
  put(r, 14, returns_byte);
  put(r, 15, class_byte);
  put(r, 16, scan_angle);
  put(r, 17, user_data);
  put(r, 18, source);
  return r;
}

// A "LASF_Projection" VLR (or, `extended`, an EVLR with its 60-byte header) holding `body`.
std::string crs_vlr(std::uint16_t record, const std::string& body, bool extended = false) {
  std::string v(extended ? 60 : 54, '\0');
  std::memcpy(v.data() + 2, "LASF_Projection", 15);
  put<std::uint16_t>(v, 18, record);
  if (extended) put<std::uint64_t>(v, 20, body.size());
  else put<std::uint16_t>(v, 20, static_cast<std::uint16_t>(body.size()));
  return v + body;
}

// GeoTIFF key directory: version 1.1.0, GTModelType 1 (projected), ProjectedCSType `epsg`, and
// a citation key pointing into the ASCII params.
std::string geokeys(std::uint16_t epsg) {
  const std::uint16_t words[] = {1, 1, 0, 3, 1024, 0, 1, 1, 1026, 34737, 22, 0, 3072, 0, 1, epsg};
  return std::string(reinterpret_cast<const char*>(words), sizeof words);
}

const char* const kUtm33Wkt =
    "PROJCS[\"WGS 84 / UTM zone 33N\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563,"
    "AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\",\"6326\"]],PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433],"
    "AUTHORITY[\"EPSG\",\"4326\"]],PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"central_meridian\",15],"
    "UNIT[\"metre\",1],AUTHORITY[\"EPSG\",\"32633\"]]";

const std::vector<double>& field(const PointCloud& cloud, const char* name) {
  const ScalarField* f = cloud.fields.find(name);
  EXPECT_NE(f, nullptr) << "missing field " << name;
  static const std::vector<double> none;
  return f ? f->values : none;
}

TEST(Las, WriteThenReadKeepsGeoreferencedPositionsAndFields) {
  const auto dir = test::temp_dir("las_roundtrip");
  const Vector3d origin(6'500'000.0, 5'200'000.0, 300.0);
  PointCloud cloud = test::sample_sphere(2000, 50.0, origin, 3);
  const std::size_t n = cloud.size();
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  // Filled first and added afterwards: FieldSet::add may move the fields already added.
  std::vector<double> intensity(n), classification(n), returns(n), return_number(n), gps_time(n);
  for (std::size_t i = 0; i < n; ++i) {
    intensity[i] = static_cast<double>(rng() % 65536);
    classification[i] = static_cast<double>(rng() % 256);
    returns[i] = 1 + static_cast<double>(rng() % 5);
    return_number[i] = 1 + static_cast<double>(rng() % static_cast<unsigned>(returns[i]));
    gps_time[i] = 3.2e8 + 0.000123 * static_cast<double>(i);
  }
  cloud.fields.add("intensity", 0, ScalarType::UInt16).values = intensity;
  cloud.fields.add("classification", 0, ScalarType::UInt8).values = classification;
  cloud.fields.add("number_of_returns", 0, ScalarType::UInt8).values = returns;
  cloud.fields.add("return_number", 0, ScalarType::UInt8).values = return_number;
  cloud.fields.add("gps_time", 0, ScalarType::Float64).values = gps_time;
  cloud.fields.add("curvature", n, ScalarType::Float32);  // no slot for it: extra bytes
  cloud.colors.resize(n);
  for (auto& c : cloud.colors) c = Vector3f(unit(rng), unit(rng), unit(rng));

  const auto path = dir / "scan.las";
  write_point_cloud(path, cloud);
  const CloudReadResult result = read_point_cloud(path);
  const PointCloud& back = result.cloud;
  EXPECT_EQ(result.format, "las");
  ASSERT_EQ(back.size(), n);
  double worst = 0;
  for (std::size_t i = 0; i < n; ++i) worst = std::max(worst, (back.positions[i] - cloud.positions[i]).cwiseAbs().maxCoeff());
  EXPECT_LE(worst, 5.0001e-5);  // half the 1e-4 quantum
  EXPECT_EQ(field(back, "intensity"), intensity);
  EXPECT_EQ(field(back, "classification"), classification);
  EXPECT_EQ(field(back, "return_number"), return_number);
  EXPECT_EQ(field(back, "number_of_returns"), returns);
  EXPECT_EQ(field(back, "gps_time"), gps_time);
  EXPECT_EQ(back.fields.find("intensity")->type, ScalarType::UInt16);
  EXPECT_EQ(back.fields.find("classification")->type, ScalarType::UInt8);
  EXPECT_EQ(back.fields.find("gps_time")->type, ScalarType::Float64);
  EXPECT_EQ(field(back, "curvature"), std::vector<double>(n, 0.0));
  EXPECT_EQ(back.fields.find("curvature")->type, ScalarType::Float32);
  EXPECT_EQ(back.fields.size(), cloud.fields.size());
  ASSERT_TRUE(back.has_normals());  // nx, ny, nz extra bytes (float32)
  for (std::size_t i = 0; i < n; ++i) EXPECT_LE((back.normals[i] - cloud.normals[i]).cwiseAbs().maxCoeff(), 1e-7);
  ASSERT_TRUE(back.has_colors());
  for (std::size_t i = 0; i < n; ++i) EXPECT_LE((back.colors[i] - cloud.colors[i]).cwiseAbs().maxCoeff(), 0.51f / 65535.0f);

  // The header: LAS 1.4, format 7 (colours), legacy counts 0 as formats 6-10 require, the
  // 64-bit count and the counts per return number; one extra bytes VLR of 4 descriptors (nx, ny,
  // nz, curvature: 16 bytes more per record).
  const std::string bytes = read_bytes(path);
  EXPECT_EQ(bytes.size(), 375 + 54 + 4 * 192 + 52 * n);
  EXPECT_EQ(bytes[24], 1);
  EXPECT_EQ(bytes[25], 4);
  EXPECT_EQ(get<std::uint16_t>(bytes, 6) & 0x10, 0x10);  // WKT bit, required for formats 6-10
  EXPECT_EQ(get<std::uint16_t>(bytes, 94), 375);
  EXPECT_EQ(get<std::uint32_t>(bytes, 96), 375u + 54u + 4u * 192u);
  EXPECT_EQ(get<std::uint32_t>(bytes, 100), 1u);
  EXPECT_EQ(bytes.substr(375 + 2, 9), "LASF_Spec");
  EXPECT_EQ(get<std::uint16_t>(bytes, 375 + 18), 4);
  EXPECT_EQ(bytes.substr(375 + 54 + 3 * 192 + 4, 9), std::string("curvature"));
  EXPECT_EQ(bytes[375 + 54 + 3 * 192 + 2], 9);  // float
  EXPECT_EQ(bytes[104], 7);
  EXPECT_EQ(get<std::uint16_t>(bytes, 105), 52);
  EXPECT_EQ(get<std::uint32_t>(bytes, 107), 0u);
  EXPECT_EQ(get<std::uint64_t>(bytes, 247), n);
  for (int r = 1; r <= 5; ++r)
    EXPECT_EQ(get<std::uint64_t>(bytes, 255 + 8 * (r - 1)), static_cast<std::uint64_t>(std::count(return_number.begin(), return_number.end(), r)));
  EXPECT_DOUBLE_EQ(get<double>(bytes, 131), 1e-4);
  EXPECT_DOUBLE_EQ(get<double>(bytes, 155), 6'499'000.0);  // minimum rounded down to 1000
  const BoundingBox box = bounding_box(back.positions);
  EXPECT_EQ(get<double>(bytes, 179), box.max.x());
  EXPECT_EQ(get<double>(bytes, 187), box.min.x());
  EXPECT_EQ(get<double>(bytes, 219), box.min.z());
}

TEST(Las, WriteWithoutColoursUsesFormat6AndAddsNoUnsetFields) {
  const auto dir = test::temp_dir("las_format6");
  PointCloud cloud = test::sample_plane(10, 2.0, 4);
  cloud.normals.clear();
  write_point_cloud(dir / "plain.las", cloud);
  const std::string bytes = read_bytes(dir / "plain.las");
  EXPECT_EQ(bytes[104], 6);
  EXPECT_EQ(bytes.size(), 375u + 30u * 10u);
  EXPECT_EQ(get<std::uint64_t>(bytes, 255), 10u);  // every point is return 1
  // The slots the cloud did not have (zero intensity, class 0, GPS time 0, return 1 of 1) do
  // not come back as fields.
  const PointCloud back = read_point_cloud(dir / "plain.las").cloud;
  EXPECT_FALSE(back.has_colors());
  EXPECT_FALSE(back.has_normals());
  EXPECT_EQ(back.fields.size(), 0u);
}

// b9_training.ply's "label" (and any field LAS has no slot for) travels as extra bytes under
// its name and type; a standard field whose values do not fit its slot does too.
TEST(Las, EveryFieldKeepsItsNameAndType) {
  const auto dir = test::temp_dir("las_extra_bytes");
  PointCloud cloud = test::sample_sphere(300, 5.0, Vector3d(596'000.0, 4'800'000.0, 20.0), 8);
  const std::size_t n = cloud.size();
  std::vector<double> label(n), deviation(n), classification(n), code(n);
  for (std::size_t i = 0; i < n; ++i) {
    label[i] = static_cast<double>(i % 9);
    deviation[i] = -0.125 + 1e-9 * static_cast<double>(i);
    classification[i] = 250.0 + static_cast<double>(i % 20);  // 250..269: beyond the slot's 255
    code[i] = -70000.0 + static_cast<double>(i);
  }
  cloud.fields.add("label", 0, ScalarType::Int32).values = label;
  cloud.fields.add("deviation", 0, ScalarType::Float64).values = deviation;
  cloud.fields.add("classification", 0, ScalarType::UInt16).values = classification;
  cloud.fields.add("code", 0, ScalarType::Int64).values = code;
  write_point_cloud(dir / "fields.las", cloud);
  const PointCloud back = read_point_cloud(dir / "fields.las").cloud;
  ASSERT_EQ(back.size(), n);
  ASSERT_EQ(back.fields.size(), 4u);
  EXPECT_EQ(field(back, "label"), label);
  EXPECT_EQ(back.fields.find("label")->type, ScalarType::Int32);
  EXPECT_EQ(field(back, "deviation"), deviation);
  EXPECT_EQ(back.fields.find("deviation")->type, ScalarType::Float64);
  EXPECT_EQ(field(back, "classification"), classification);
  EXPECT_EQ(field(back, "code"), code);
  ASSERT_TRUE(back.has_normals());

  PointCloud long_name = test::sample_plane(5, 1.0, 2);
  long_name.fields.add(std::string(33, 'a'), 5, ScalarType::Float32);
  EXPECT_TRUE(test::contains(test::error_of<UsageError>([&] { write_point_cloud(dir / "long.las", long_name); }),
                             "names hold at most 32 characters"));
}

TEST(Las, WriteHonoursScaleAndOffsetAndWidensTheDefaultScaleForHugeExtents) {
  const auto dir = test::temp_dir("las_scale");
  PointCloud cloud;
  cloud.positions = {Vector3d(-600'000.0, 0.25, 1.0), Vector3d(600'000.0, -0.25, 2.0)};
  write_point_cloud(dir / "wide.las", cloud);
  std::string bytes = read_bytes(dir / "wide.las");
  EXPECT_DOUBLE_EQ(get<double>(bytes, 131), 1e-3);  // 1.2e6 m does not fit 32 bits at 1e-4
  EXPECT_DOUBLE_EQ(get<double>(bytes, 139), 1e-4);
  const PointCloud back = read_point_cloud(dir / "wide.las").cloud;
  for (std::size_t i = 0; i < 2; ++i) EXPECT_LE((back.positions[i] - cloud.positions[i]).norm(), 1e-3);

  WriteOptions options;
  options.las_scale = 0.5;
  options.las_offset = Vector3d(10, 20, 30);
  write_point_cloud(dir / "coarse.las", cloud, options);
  bytes = read_bytes(dir / "coarse.las");
  EXPECT_EQ(get<double>(bytes, 131), 0.5);
  EXPECT_EQ(get<double>(bytes, 163), 20.0);
  EXPECT_EQ(get<std::int32_t>(bytes, 375 + 8), static_cast<std::int32_t>(std::lround((1.0 - 30.0) / 0.5)));

  options.las_scale = 1e-5;
  expect_error<UsageError>([&] { write_point_cloud(dir / "overflow.las", cloud, options); }, "cannot hold x = -600000 in 32 bits");
  EXPECT_FALSE(std::filesystem::exists(dir / "overflow.las"));
  options.las_scale = 0.0;
  expect_error<UsageError>([&] { write_point_cloud(dir / "zero.las", cloud, options); }, "must be a positive number");

  // An offset far from georeferenced data would coarsen the default scale 1e-4 to 1e-3: refused,
  // with the scale it needs; given that scale explicitly, it is written.
  PointCloud tile;
  tile.positions = {Vector3d(590'000.25, 4'500.5, 10.0), Vector3d(590'500.75, 4'900.25, 30.0)};
  WriteOptions zero_offset;
  zero_offset.las_offset = Vector3d::Zero();
  expect_error<UsageError>([&] { write_point_cloud(dir / "far.las", tile, zero_offset); },
                           "LAS offset x = 0 is too far from the data (590000.25 up to 590500.75) for the default scale 1e-4: it would need 0.001");
  EXPECT_FALSE(std::filesystem::exists(dir / "far.las"));
  zero_offset.las_scale = 1e-3;
  write_point_cloud(dir / "far.las", tile, zero_offset);
  EXPECT_DOUBLE_EQ(get<double>(read_bytes(dir / "far.las"), 131), 1e-3);
  zero_offset = {};
  zero_offset.las_offset = Vector3d(590'000, 0, 0);  // near the data: the default scale holds
  write_point_cloud(dir / "near.las", tile, zero_offset);
  EXPECT_DOUBLE_EQ(get<double>(read_bytes(dir / "near.las"), 131), 1e-4);
}

// Issue 28: a LAS round trip kept 0.001 as 0.0001. A cloud read from LAS or LAZ keeps the
// file's scale and offset on the next LAS or LAZ write, unless the options say otherwise or the
// points no longer fit that grid in 32 bits.
TEST(Las, RoundTripKeepsTheInputsScaleAndOffset) {
  const auto dir = test::temp_dir("las_keep_scale");
  PointCloud tile;
  for (int i = 0; i < 50; ++i) tile.positions.emplace_back(431'000.0 + 0.001 * (37 * i), 5'200'000.0 + 0.001 * (11 * i), 100.0 + 0.001 * i);
  WriteOptions millimetres;
  millimetres.las_scale = 0.001;
  millimetres.las_offset = Vector3d(431'000, 5'200'000, 0);
  write_point_cloud(dir / "in.las", tile, millimetres);
  const CloudReadResult in = read_point_cloud(dir / "in.las");
  EXPECT_EQ(in.cloud.grid.scale, Vector3d::Constant(0.001));
  EXPECT_EQ(in.cloud.grid.offset, Vector3d(431'000, 5'200'000, 0));
  const std::string source = read_bytes(dir / "in.las");
  for (const char* out : {"out.las", "out.laz"}) {
    SCOPED_TRACE(out);
    const WriteResult w = write_point_cloud(dir / out, in.cloud);
    EXPECT_TRUE(w.notes.empty());
    const CloudReadResult back = read_point_cloud(dir / out);
    EXPECT_EQ(back.cloud.grid, in.cloud.grid);
    const std::string bytes = read_bytes(dir / out);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(get<double>(bytes, 131 + 8 * a), 0.001);
      EXPECT_EQ(get<double>(bytes, 155 + 8 * a), get<double>(source, 155 + 8 * a));
    }
    ASSERT_EQ(back.cloud.positions, in.cloud.positions);  // the same integers, so the same doubles
  }
  // Asked otherwise: the options win, each for its own part.
  WriteOptions finer;
  finer.las_scale = 1e-4;
  write_point_cloud(dir / "finer.las", in.cloud, finer);
  EXPECT_EQ(read_point_cloud(dir / "finer.las").cloud.grid, (CoordinateGrid{Vector3d::Constant(1e-4), Vector3d(431'000, 5'200'000, 0)}));
  // Moved far from the offset: the grid cannot hold the points, the default is used and a note says so.
  PointCloud moved = in.cloud;
  for (Vector3d& p : moved.positions) p.x() += 3'000'000.0;
  const WriteResult w = write_point_cloud(dir / "moved.las", moved);
  ASSERT_EQ(w.notes.size(), 1u);
  EXPECT_TRUE(test::contains(w.notes[0], "no longer fit the input's LAS grid (scale 0.001 0.001 0.001, offset 431000 5200000 0)")) << w.notes[0];
  EXPECT_EQ(read_point_cloud(dir / "moved.las").cloud.grid.scale, Vector3d::Constant(1e-4));
  // A grid from elsewhere (PLY, text) is none: the default 1e-4 as before.
  PointCloud plain = in.cloud;
  plain.grid = {};
  write_point_cloud(dir / "plain.las", plain);
  EXPECT_EQ(get<double>(read_bytes(dir / "plain.las"), 131), 1e-4);
}

TEST(Las, EmptyCloudRoundTrips) {
  const auto dir = test::temp_dir("las_empty");
  write_point_cloud(dir / "empty.las", PointCloud{});
  EXPECT_EQ(read_point_cloud(dir / "empty.las").cloud.size(), 0u);
}

TEST(Las, ReadsHandBuiltLas12Format3WithVlr) {
  const auto dir = test::temp_dir("las12_format3");
  LasFile las;
  las.format = 3;
  las.record_length = 34;
  las.legacy_count = 2;
  las.offset[0] = 1000;
  las.offset[1] = 2000;
  las.offset[2] = 3000;
  las.vlrs = projection_vlr();
  // Return 2 of 3 with the scan direction bit set; class 6 with the synthetic flag set.
  std::string p0 = legacy_record(34, 100, -200, 300, 500, 2 | (3 << 3) | 0x40, 6 | 0x20, -15, 7, 42);
  put<double>(p0, 20, 123456.789);
  put<std::uint16_t>(p0, 28, 65535);
  put<std::uint16_t>(p0, 30, 32768);
  put<std::uint16_t>(p0, 32, 0);
  std::string p1 = legacy_record(34, -1, 0, 1, 65535, 1 | (1 << 3), 2, 30, 0, 0);
  put<double>(p1, 20, -1.5);
  put<std::uint16_t>(p1, 28, 256);
  las.points = p0 + p1;

  const CloudReadResult result = read_point_cloud(write_bytes(dir / "f3.las", las.bytes()));
  const PointCloud& c = result.cloud;
  EXPECT_EQ(result.encoding, "LAS 1.2 point format 3");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_NEAR((c.positions[0] - Vector3d(1001.0, 1998.0, 3003.0)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((c.positions[1] - Vector3d(999.99, 2000.0, 3000.01)).norm(), 0.0, 1e-9);
  EXPECT_EQ(field(c, "intensity"), (std::vector<double>{500, 65535}));
  EXPECT_EQ(field(c, "return_number"), (std::vector<double>{2, 1}));
  EXPECT_EQ(field(c, "number_of_returns"), (std::vector<double>{3, 1}));
  EXPECT_EQ(field(c, "classification"), (std::vector<double>{6, 2}));
  EXPECT_EQ(field(c, "gps_time"), (std::vector<double>{123456.789, -1.5}));
  EXPECT_EQ(field(c, "scan_angle"), (std::vector<double>{-15, 30}));
  EXPECT_EQ(field(c, "user_data"), (std::vector<double>{7, 0}));
  EXPECT_EQ(field(c, "point_source_id"), (std::vector<double>{42, 0}));
  ASSERT_TRUE(c.has_colors());
  EXPECT_EQ(c.colors[0], Vector3f(1.0f, 32768 / 65535.0f, 0.0f));
  EXPECT_EQ(c.colors[1], Vector3f(256 / 65535.0f, 0.0f, 0.0f));
}

TEST(Las, ReadsHandBuiltLas12Format1) {
  const auto dir = test::temp_dir("las12_format1");
  LasFile las;
  las.format = 1;
  las.record_length = 28;
  las.legacy_count = 1;
  las.scale[2] = 0.001;
  std::string p = legacy_record(28, 12345, 67890, -5, 7, 1 | (2 << 3), 9, 0, 0, 0);
  put<double>(p, 20, 42.25);
  las.points = p;
  const PointCloud c = read_point_cloud(write_bytes(dir / "f1.las", las.bytes())).cloud;
  ASSERT_EQ(c.size(), 1u);
  EXPECT_NEAR((c.positions[0] - Vector3d(123.45, 678.90, -0.005)).norm(), 0.0, 1e-12);
  EXPECT_EQ(field(c, "gps_time"), std::vector<double>{42.25});
  EXPECT_EQ(field(c, "classification"), std::vector<double>{9});
  EXPECT_FALSE(c.has_colors());
  EXPECT_FALSE(c.fields.contains("scan_angle"));  // all zero: not kept
}

TEST(Las, ReadsHandBuiltLas13Format0WithExtraBytes) {
  const auto dir = test::temp_dir("las13_format0");
  LasFile las;
  las.minor = 3;
  las.format = 0;
  las.record_length = 24;  // 4 extra bytes per record, skipped
  las.legacy_count = 3;
  for (int i = 0; i < 3; ++i) {
    std::string r = legacy_record(24, i * 100, i * 200, i * 300, static_cast<std::uint16_t>(10 * i), 1 | (1 << 3), 2, 0, 0, 0);
    put<std::int32_t>(r, 20, -1);
    las.points += r;
  }
  const CloudReadResult result = read_point_cloud(write_bytes(dir / "f0.las", las.bytes()));
  const PointCloud& c = result.cloud;
  EXPECT_EQ(result.encoding, "LAS 1.3 point format 0");
  ASSERT_EQ(c.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR((c.positions[i] - Vector3d(i * 1.0, i * 2.0, i * 3.0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(field(c, "intensity"), (std::vector<double>{0, 10, 20}));
  EXPECT_FALSE(c.fields.contains("gps_time"));
}

TEST(Las, ReadsLas14Format6WithOnlyThe64BitCount) {
  const auto dir = test::temp_dir("las14_format6");
  LasFile las;
  las.minor = 4;
  las.format = 6;
  las.record_length = 30;
  las.legacy_count = 0;
  las.count64 = 2;
  for (int i = 0; i < 2; ++i) {
    std::string r(30, '\0');
    put<std::int32_t>(r, 0, 1000 + i);
    put<std::uint16_t>(r, 12, 77);
    put<std::uint8_t>(r, 14, static_cast<std::uint8_t>(9 | (12 << 4)));  // return 9 of 12
    put<std::uint8_t>(r, 15, 0xFF);                                       // flags, channel, direction, edge
    put<std::uint8_t>(r, 16, 200);                                        // a class only 6-10 hold
    put<std::int16_t>(r, 18, -2500);                                      // -15 degrees in 0.006 steps
    put<std::uint16_t>(r, 20, 3);
    put<double>(r, 22, 1e9 + i);
    las.points += r;
  }
  const PointCloud c = read_point_cloud(write_bytes(dir / "f6.las", las.bytes())).cloud;
  ASSERT_EQ(c.size(), 2u);
  EXPECT_NEAR(c.positions[1].x(), 10.01, 1e-12);
  EXPECT_EQ(field(c, "return_number"), (std::vector<double>{9, 9}));
  EXPECT_EQ(field(c, "number_of_returns"), (std::vector<double>{12, 12}));
  EXPECT_EQ(field(c, "classification"), (std::vector<double>{200, 200}));
  EXPECT_NEAR(field(c, "scan_angle")[0], -15.0, 1e-12);
  EXPECT_EQ(field(c, "point_source_id"), (std::vector<double>{3, 3}));
  EXPECT_EQ(field(c, "gps_time"), (std::vector<double>{1e9, 1e9 + 1}));
}

// Extra bytes as another writer lays them out: an undefined 2-byte run (type 0) to skip, a
// scaled and offset uint16 and a float, after a projection VLR.
TEST(Las, ReadsExtraBytesByTheirDescriptors) {
  const auto dir = test::temp_dir("las_extra_descriptors");
  std::string vlr(54 + 3 * 192, '\0');
  std::memcpy(vlr.data() + 2, "LASF_Spec", 9);
  put<std::uint16_t>(vlr, 18, 4);
  put<std::uint16_t>(vlr, 20, 3 * 192);
  const auto descriptor = [&](int d, int type, int options, const char* name) {
    const std::size_t at = 54 + 192 * std::size_t(d);
    vlr[at + 2] = static_cast<char>(type);
    vlr[at + 3] = static_cast<char>(options);
    std::memcpy(vlr.data() + at + 4, name, std::strlen(name));
    return at;
  };
  descriptor(0, 0, 2, "padding");
  const std::size_t height = descriptor(1, 3, 0x18, "Height Above Ground");  // scale and offset
  put<double>(vlr, height + 112, 0.01);
  put<double>(vlr, height + 136, -5.0);
  descriptor(2, 9, 0, "reflectance");
  LasFile las;
  las.minor = 4;
  las.format = 6;
  las.record_length = 30 + 2 + 2 + 4;
  las.count64 = 2;
  las.vlrs = projection_vlr() + vlr;
  for (int i = 0; i < 2; ++i) {
    std::string r(las.record_length, '\0');
    put<std::int32_t>(r, 0, i);
    put<std::uint16_t>(r, 32, static_cast<std::uint16_t>(1000 + i));
    put<float>(r, 34, 0.5f * static_cast<float>(i + 1));
    las.points += r;
  }
  std::string bytes = las.bytes();
  put<std::uint32_t>(bytes, 100, 2);  // two VLRs
  const CloudReadResult result = read_point_cloud(write_bytes(dir / "extra.las", bytes));
  const PointCloud& c = result.cloud;
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.fields.size(), 2u);  // no unset slots, the padding skipped
  EXPECT_EQ(field(c, "Height Above Ground"), (std::vector<double>{1000 * 0.01 - 5.0, 1001 * 0.01 - 5.0}));
  EXPECT_EQ(c.fields.find("Height Above Ground")->type, ScalarType::Float64);
  EXPECT_EQ(field(c, "reflectance"), (std::vector<double>{0.5, 1.0}));
  EXPECT_EQ(c.fields.find("reflectance")->type, ScalarType::Float32);
  ASSERT_EQ(result.warnings.size(), 1u);
  EXPECT_TRUE(test::contains(result.warnings[0], "extra bytes 'padding' of data type 0 skipped")) << result.warnings[0];
}

TEST(Las, EightBitColoursStoredUnscaledAreReadAsEightBit) {
  const auto dir = test::temp_dir("las_rgb8");
  LasFile las;
  las.format = 2;
  las.record_length = 26;
  las.legacy_count = 1;
  std::string p = legacy_record(26, 0, 0, 0, 0, 1 | (1 << 3), 0, 0, 0, 0);
  put<std::uint16_t>(p, 20, 255);
  put<std::uint16_t>(p, 22, 51);
  put<std::uint16_t>(p, 24, 0);
  las.points = p;
  const CloudReadResult result = read_point_cloud(write_bytes(dir / "rgb8.las", las.bytes()));
  ASSERT_TRUE(result.cloud.has_colors());
  EXPECT_EQ(result.cloud.colors[0], Vector3f(1.0f, 51 / 255.0f, 0.0f));
  ASSERT_EQ(result.warnings.size(), 1u);
  EXPECT_NE(result.warnings[0].find("8-bit"), std::string::npos);
}

TEST(Las, TruncatedPointDataNamesThePointAndTheByte) {
  const auto dir = test::temp_dir("las_truncated");
  LasFile las;
  las.legacy_count = 5;
  for (int i = 0; i < 3; ++i) las.points += legacy_record(20, i, i, i, 0, 9, 0, 0, 0, 0);
  las.points += std::string(7, '\0');  // a partial fourth record
  const auto path = write_bytes(dir / "scan.las", las.bytes());
  expect_error<InputError>([&] { read_point_cloud(path); }, "scan.las: point 3 of 5: file ends at byte 294");
}

TEST(Las, PointCountBeyondTheFileIsRejectedBeforeAllocating) {
  const auto dir = test::temp_dir("las_huge_count");
  LasFile las;
  las.minor = 4;
  las.format = 6;
  las.record_length = 30;
  las.count64 = 1'000'000'000'000ULL;
  las.points = std::string(30, '\0');
  expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "huge.las", las.bytes())); }, "point 1 of 1000000000000: file ends");
  LasFile legacy;
  legacy.legacy_count = 0xFFFFFFFFu;
  expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "legacy.las", legacy.bytes())); }, "point 0 of 4294967295");
}

TEST(Las, MalformedHeadersAreInputErrors) {
  const auto dir = test::temp_dir("las_bad_headers");
  {
    LasFile las;
    las.format = 11;
    las.record_length = 40;
    expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "f11.las", las.bytes())); },
                             "f11.las: point data record format 11 is not supported: expected 0 to 10");
  }
  {
    LasFile las;
    las.format = 3;
    las.record_length = 30;
    expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "short_record.las", las.bytes())); },
                             "point record length 30 is shorter than the 34 bytes point format 3 needs");
  }
  {
    LasFile las;
    las.minor = 5;
    expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "v15.las", las.bytes())); }, "unsupported LAS version 1.5");
  }
  {
    LasFile las;
    las.minor = 4;
    las.header_size = 227;  // a 1.4 header needs 375 bytes
    expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "short14.las", las.bytes())); }, "header too short");
  }
  {
    const std::string cut = LasFile{}.bytes().substr(0, 100);
    expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "cut.las", cut)); },
                             "cut.las: header too short: the file has 100 bytes");
  }
  {
    LasFile las;
    las.scale[1] = 0.0;
    expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "scale0.las", las.bytes())); }, "y scale factor is 0");
  }
  {
    ReadOptions forced;
    forced.format = "las";
    expect_error<InputError>([&] { read_point_cloud(write_bytes(dir / "text.las", "1 2 3\n"), forced); }, "expected the signature 'LASF'");
  }
}

TEST(Las, GeoTiffKeysOfAHandBuiltFileAreReadAndWrittenBackByteForByteToLasAndLaz) {
  const auto dir = test::temp_dir("las_geotiff");
  LasFile las;
  las.legacy_count = 1;
  const std::string keys = geokeys(32633), doubles(16, '\x42'), ascii("WGS 84 / UTM zone 33N|\0", 23);
  las.vlrs = crs_vlr(34735, keys) + crs_vlr(34736, doubles) + crs_vlr(34737, ascii);
  las.vlr_count = 3;
  las.points = legacy_record(20, 100, 200, 300, 0, 1 | (1 << 3), 2, 0, 0, 0);
  const PointCloud c = read_point_cloud(write_bytes(dir / "keys.las", las.bytes())).cloud;
  auto bytes = [](const std::string& s) { return std::vector<std::uint8_t>(s.begin(), s.end()); };
  EXPECT_EQ(c.crs.geokeys, bytes(keys));
  EXPECT_EQ(c.crs.geodouble, bytes(doubles));
  EXPECT_EQ(c.crs.geoascii, bytes(ascii));
  EXPECT_TRUE(c.crs.wkt.empty());
  EXPECT_EQ(c.crs.epsg(), 32633);
  EXPECT_EQ(c.crs.describe(), "EPSG:32633 (GeoTIFF keys)");
  for (const char* out : {"keys_out.las", "keys_out.laz"}) {
    const WriteResult written = write_point_cloud(dir / out, c);
    ASSERT_EQ(written.notes.size(), 1u) << out;
    EXPECT_NE(written.notes[0].find("GeoTIFF keys only"), std::string::npos) << written.notes[0];
    const PointCloud back = read_point_cloud(dir / out).cloud;
    EXPECT_EQ(back.crs.geokeys, c.crs.geokeys) << out;
    EXPECT_EQ(back.crs.geodouble, c.crs.geodouble) << out;
    EXPECT_EQ(back.crs.geoascii, c.crs.geoascii) << out;
    EXPECT_TRUE(back.crs.wkt.empty()) << out;
  }
}

TEST(Las, WktIsWrittenAsANullTerminatedVlrAndReadBackFromLasLazAndEvlrs) {
  const auto dir = test::temp_dir("las_wkt");
  PointCloud cloud = test::sample_sphere(50, 10.0, Vector3d(500'000.0, 5'000'000.0, 100.0), 5);
  cloud.crs.wkt = kUtm33Wkt;
  EXPECT_EQ(cloud.crs.describe(), "WGS 84 / UTM zone 33N (EPSG:32633)");
  EXPECT_EQ(cloud.select(std::vector<std::size_t>{0, 1}).crs.wkt, cloud.crs.wkt);
  write_point_cloud(dir / "wkt.las", cloud);
  const std::string file = read_bytes(dir / "wkt.las");
  EXPECT_EQ(get<std::uint16_t>(file, 6) & 0x10, 0x10);  // global encoding: the CRS is WKT
  const std::string body = std::string(kUtm33Wkt) + '\0';
  const std::size_t at = file.find(body);
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(get<std::uint16_t>(file, at - 54 + 18), 2112);
  EXPECT_EQ(get<std::uint16_t>(file, at - 54 + 20), body.size());
  for (const char* out : {"wkt.las", "wkt.laz"}) {
    if (std::string(out) == "wkt.laz") write_point_cloud(dir / out, cloud);
    const PointCloud back = read_point_cloud(dir / out).cloud;
    EXPECT_EQ(back.crs.wkt, cloud.crs.wkt) << out;
    EXPECT_TRUE(back.crs.geokeys.empty()) << out;
  }

  // A LAS 1.4 file whose WKT is an extended VLR after the points.
  LasFile las;
  las.minor = 4;
  las.format = 6;
  las.record_length = 30;
  las.count64 = 1;
  las.points = std::string(30, '\0');
  put<std::uint8_t>(las.points, 14, 1 | (1 << 4));
  las.evlrs = crs_vlr(2112, body, true);
  las.evlr_count = 1;
  const PointCloud evlr = read_point_cloud(write_bytes(dir / "evlr.las", las.bytes())).cloud;
  EXPECT_EQ(evlr.crs.wkt, kUtm33Wkt);
  ASSERT_EQ(evlr.size(), 1u);
}

}  // namespace
}  // namespace pointsurf
