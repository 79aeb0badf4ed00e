// SPDX-License-Identifier: GPL-3.0-or-later
// LAZ: the reference files written by LASzip (tests/data, provenance in its README) decoded
// identically to their uncompressed twin, LASzip's own bytes reproduced by the encoder, records
// of every supported point format through encode then decode bit for bit, cloud round trips,
// and every corruption path refused with the file and the chunk named.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "io/detail/laz_items.h"
#include "io/detail/laz_layered.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

namespace laz = io::detail::laz;
using test::read_bytes;
using test::write_bytes;

static_assert(std::endian::native == std::endian::little, "the files below are taken apart in host byte order");


using test::get;
using test::put;

// One name per process: ctest runs each test in its own process, in parallel.
std::filesystem::path temp(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("pointsurf_laz_" + std::to_string(::getpid()) + "_" + name);
}

void expect_same_clouds(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a.positions[i], b.positions[i]) << "point " << i;
  ASSERT_EQ(a.colors.size(), b.colors.size());
  for (std::size_t i = 0; i < a.colors.size(); ++i) ASSERT_EQ(a.colors[i], b.colors[i]) << "point " << i;
  ASSERT_EQ(a.normals.size(), b.normals.size());
  for (std::size_t i = 0; i < a.normals.size(); ++i) ASSERT_EQ(a.normals[i], b.normals[i]) << "point " << i;
  ASSERT_EQ(a.fields.size(), b.fields.size());
  for (const ScalarField& f : a.fields) {
    const ScalarField* g = b.fields.find(f.name);
    ASSERT_NE(g, nullptr) << f.name;
    EXPECT_EQ(f.type, g->type) << f.name;
    ASSERT_EQ(f.values, g->values) << f.name;
  }
}

TEST(Laz, ReferenceFileDecodesIdenticallyToItsLasTwin) {
  const PointCloud las = read_point_cloud(test::test_data_path("simple.las")).cloud;
  const PointCloud laz = read_point_cloud(test::test_data_path("simple.laz")).cloud;
  ASSERT_EQ(las.size(), 1065u);
  expect_same_clouds(las, laz);
}

// The point records themselves: LASzip's chunk decoded to the LAS file's bytes, and the LAS
// records encoded to LASzip's bytes (the coder matches LASzip's bit for bit, not only itself).
TEST(Laz, ChunkOfLaszipDecodesToTheLasRecordsAndReencodesToTheSameBytes) {
  const std::string las = read_bytes(test::test_data_path("simple.las"));
  const std::string lzf = read_bytes(test::test_data_path("simple.laz"));
  ASSERT_FALSE(las.empty());
  ASSERT_FALSE(lzf.empty());
  const std::size_t n = get<std::uint32_t>(las, 107), record = get<std::uint16_t>(las, 105);
  const std::size_t las_points = get<std::uint32_t>(las, 96);
  const std::size_t laz_points = get<std::uint32_t>(lzf, 96);
  const auto table_at = static_cast<std::size_t>(get<std::int64_t>(lzf, laz_points));
  // The LASzip VLR is the file's only VLR, right after the 227-byte header.
  const laz::LaszipVlr vlr = laz::LaszipVlr::parse(std::string_view(lzf).substr(227 + 54, get<std::uint16_t>(lzf, 227 + 20)));
  EXPECT_EQ(vlr.compressor, 2);
  EXPECT_EQ(vlr.chunk_size, 50000u);
  ASSERT_EQ(vlr.record_size(), record);

  const auto* chunk = reinterpret_cast<const unsigned char*>(lzf.data() + laz_points + 8);
  const std::size_t chunk_size = table_at - laz_points - 8;
  laz::ChunkDecoder decoder(vlr);
  decoder.start(chunk, chunk_size);
  std::string out(record, '\0');
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_TRUE(decoder.next(out.data())) << "point " << i;
    ASSERT_EQ(out, las.substr(las_points + i * record, record)) << "point " << i;
  }

  std::vector<unsigned char> encoded;
  laz::ChunkEncoder encoder(vlr, encoded);
  encoder.start();
  for (std::size_t i = 0; i < n; ++i) encoder.add(las.data() + las_points + i * record);
  encoder.finish();
  ASSERT_EQ(encoded.size(), chunk_size);
  EXPECT_TRUE(std::equal(encoded.begin(), encoded.end(), chunk));

  // The chunk table: one chunk of that many bytes, coded as LASzip codes it.
  const laz::ChunkTable table = laz::decode_chunk_table(reinterpret_cast<const unsigned char*>(lzf.data() + table_at), lzf.size() - table_at, false);
  ASSERT_EQ(table.bytes.size(), 1u);
  EXPECT_EQ(table.bytes[0], chunk_size);
  EXPECT_EQ(laz::encode_chunk_table(table, false), lzf.substr(table_at));
}

TEST(Laz, ExtraBytesOfTheReferenceFileBecomeNamedFields) {
  const PointCloud cloud = read_point_cloud(test::test_data_path("extra.laz")).cloud;
  const PointCloud twin = read_point_cloud(test::test_data_path("simple.las")).cloud;
  ASSERT_EQ(cloud.size(), twin.size());
  for (const char* name : {"Colors_0", "Colors_1", "Colors_2", "Flags_0", "Flags_1", "Intensity", "Time"})
    EXPECT_NE(cloud.fields.find(name), nullptr) << name;
  // The file's extra bytes repeat the standard attributes: intensity and the GPS time (whole seconds).
  const auto& intensity = cloud.fields.find("Intensity")->values;
  const auto& time = cloud.fields.find("Time")->values;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(intensity[i], twin.fields.find("intensity")->values[i]) << i;
    ASSERT_EQ(time[i], std::floor(twin.fields.find("gps_time")->values[i])) << i;
  }

  // Written as LAZ and read back, every field keeps its name, type and values (the scan angle
  // to LAS 1.4's steps of 0.006 degrees).
  const auto path = temp("extra_round_trip.laz");
  write_point_cloud(path, cloud);
  const PointCloud back = read_point_cloud(path).cloud;
  ASSERT_EQ(back.size(), cloud.size());
  for (const ScalarField& f : cloud.fields) {
    const ScalarField* g = back.fields.find(f.name);
    ASSERT_NE(g, nullptr) << f.name;
    if (f.name == "scan_angle") {
      for (std::size_t i = 0; i < f.values.size(); ++i) ASSERT_NEAR(f.values[i], g->values[i], 0.003) << i;
    } else {
      EXPECT_EQ(f.values, g->values) << f.name;
    }
  }
  std::filesystem::remove(path);
}

// Encodes `records` in chunks of `chunk` points, decodes them back and expects the same bytes;
// the coded size must be below the records'.
void expect_round_trip(const laz::LaszipVlr& vlr, const std::string& records, std::size_t chunk, int format) {
  const std::size_t record = vlr.record_size(), n = records.size() / record;
  std::vector<unsigned char> coded;
  laz::ChunkEncoder encoder(vlr, coded);
  std::vector<std::size_t> ends;
  for (std::size_t first = 0; first < n; first += chunk) {
    encoder.start();
    for (std::size_t i = first; i < std::min(n, first + chunk); ++i) encoder.add(records.data() + i * record);
    encoder.finish();
    ends.push_back(coded.size());
  }
  laz::ChunkDecoder decoder(vlr);
  std::string out(record, '\0');
  std::size_t begin = 0;
  for (std::size_t c = 0; c < ends.size(); ++c) {
    decoder.start(coded.data() + begin, ends[c] - begin);
    for (std::size_t i = c * chunk; i < std::min(n, (c + 1) * chunk); ++i) {
      ASSERT_TRUE(decoder.next(out.data())) << "format " << format << " point " << i;
      ASSERT_EQ(out, records.substr(i * record, record)) << "format " << format << " point " << i;
    }
    begin = ends[c];
  }
  EXPECT_LT(coded.size(), records.size()) << "format " << format;
}

// Random records with the structure the predictors exploit: a walk in x and y, z with jumps,
// intensity in runs, GPS time in pulse steps with repeats and jumps between sequences, grey and
// coloured points.
struct RecordWalk {
  explicit RecordWalk(unsigned seed) : rng(seed) {}
  void xyz_intensity(char* r) {
    x += static_cast<std::int32_t>(rng() % 200) - 100;
    y += static_cast<std::int32_t>(rng() % 2000) - 1000;
    z = static_cast<std::int32_t>(rng() % 7 == 0 ? rng() : z + rng() % 50);
    std::memcpy(r, &x, 4);
    std::memcpy(r + 4, &y, 4);
    std::memcpy(r + 8, &z, 4);
    const auto intensity = static_cast<std::uint16_t>(rng() % 3 ? 500 + rng() % 20 : rng());
    std::memcpy(r + 12, &intensity, 2);
  }
  void time(char* r) {
    const unsigned kind = rng() % 20;
    if (kind == 0) t += 1e7;
    else if (kind == 1) t -= 5e6;
    else if (kind > 3) t += 1e-5 * (1 + rng() % 3);
    std::memcpy(r, &t, 8);
  }
  void colour(char* r, int channels) {
    const auto grey = static_cast<std::uint16_t>(rng() % 65536);
    for (int c = 0; c < channels; ++c) {
      const auto v = static_cast<std::uint16_t>(rng() % 2 ? grey : grey + rng() % 300);
      std::memcpy(r + 2 * c, &v, 2);
    }
  }
  // A wave packet descriptor: index, waveform offset (repeated, following, near or far), size,
  // return point and direction.
  void wave(char* r) {
    r[0] = static_cast<char>(1 + rng() % 3);
    const unsigned kind = rng() % 4;
    if (kind == 1) offset += size;
    else if (kind == 2) offset += rng() % 5000;
    else if (kind == 3) offset = (std::uint64_t(rng()) << 32) | rng();
    if (rng() % 5 == 0) size = 256 + rng() % 64;
    const float f[4] = {float(rng() % 1000) * 0.5f, 1e-4f * float(rng() % 100), -2e-4f, 0.9f};
    std::memcpy(r + 1, &offset, 8);
    std::memcpy(r + 9, &size, 4);
    std::memcpy(r + 13, f, 16);
  }
  std::uint64_t offset = 1000;
  std::uint32_t size = 256;
  void source(char* r) {
    const auto id = static_cast<std::uint16_t>(rng() % 50 ? 7 : rng());
    std::memcpy(r, &id, 2);
  }
  std::mt19937 rng;
  std::int32_t x = 0, y = 0, z = 0;
  double t = 1000.0;
};

// Records of point formats 0-5 with extra bytes: random values with the structure the
// predictors exploit (runs, several GPS time sequences, grey and coloured points), through
// several chunks, decode to the same bytes.
TEST(Laz, EveryPointwiseFormatRoundTripsBitForBit) {
  for (int format = 0; format <= 5; ++format) {
    for (std::size_t extra : {std::size_t(0), std::size_t(5)}) {
      laz::LaszipVlr vlr;
      vlr.items = laz::pointwise_items(format, extra);
      const std::size_t record = vlr.record_size();
      RecordWalk walk(static_cast<unsigned>(17 + format * 10 + extra));
      auto& rng = walk.rng;
      const std::size_t n = 3000;
      std::string records(n * record, '\0');
      for (std::size_t i = 0; i < n; ++i) {
        char* r = records.data() + i * record;
        walk.xyz_intensity(r);
        const unsigned rets = 1 + rng() % 5, ret = 1 + rng() % rets;
        r[14] = static_cast<char>(ret | (rets << 3) | ((rng() % 9 == 0) << 6) | ((rng() % 31 == 0) << 7));
        r[15] = static_cast<char>(rng() % 4 ? 2 : rng());
        r[16] = static_cast<char>(static_cast<int>(rng() % 181) - 90);
        r[17] = static_cast<char>(rng() % 10 ? 0 : rng());
        walk.source(r + 18);
        std::size_t at = 20;
        if (format == 1 || format >= 3) {
          walk.time(r + at);
          at += 8;
        }
        if (format == 2 || format == 3 || format == 5) {
          walk.colour(r + at, 3);
          at += 6;
        }
        if (format >= 4) {
          walk.wave(r + at);
          at += 29;
        }
        for (std::size_t e = 0; e < extra; ++e) r[at + e] = static_cast<char>(e == 0 ? rng() : i / 7);
      }
      expect_round_trip(vlr, records, 1000, format);
    }
  }
}

// Point formats 6-10 (layered compressor): returns up to 15, classes up to 255, flags, 16-bit
// scan angles, NIR, and scanner channel switches (each channel has its own models).
TEST(Laz, EveryLayeredFormatRoundTripsBitForBit) {
  for (int format = 6; format <= 10; ++format) {
    for (std::size_t extra : {std::size_t(0), std::size_t(3)}) {
      for (bool channels : {false, true}) {
        laz::LaszipVlr vlr;
        vlr.compressor = 3;
        vlr.items = laz::layered_items(format, extra);
        const std::size_t record = vlr.record_size();
        RecordWalk walk(static_cast<unsigned>(5 + format * 10 + extra + channels));
        auto& rng = walk.rng;
        const std::size_t n = 3000;
        std::string records(n * record, '\0');
        std::int16_t angle = 0;
        unsigned channel = 0;
        for (std::size_t i = 0; i < n; ++i) {
          char* r = records.data() + i * record;
          walk.xyz_intensity(r);
          const unsigned rets = rng() % 20 == 0 ? rng() % 16 : 1 + rng() % 4, ret = rng() % 20 == 0 ? rng() % 16 : 1 + rng() % (rets ? rets : 1);
          r[14] = static_cast<char>(ret | (rets << 4));
          if (channels && rng() % 40 == 0) channel = rng() % 4;
          r[15] = static_cast<char>((rng() % 30 == 0 ? rng() % 16 : 0) | (channel << 4) | ((rng() % 9 == 0) << 6) | ((rng() % 31 == 0) << 7));
          r[16] = static_cast<char>(rng() % 4 ? 2 : rng());
          r[17] = static_cast<char>(rng() % 10 ? 0 : rng());
          if (rng() % 5 == 0) angle = static_cast<std::int16_t>(angle + static_cast<int>(rng() % 2001) - 1000);
          std::memcpy(r + 18, &angle, 2);
          walk.source(r + 20);
          walk.time(r + 22);
          std::size_t at = 30;
          if (format == 7 || format == 8 || format == 10) {
            walk.colour(r + at, format == 7 ? 3 : 4);
            at += format == 7 ? 6 : 8;
          }
          if (format >= 9) {
            walk.wave(r + at);
            at += 29;
          }
          for (std::size_t e = 0; e < extra; ++e) r[at + e] = static_cast<char>(e == 0 ? rng() : i / 7);
        }
        expect_round_trip(vlr, records, 1000, format);
      }
    }
  }
}

// simple.las recompressed by hand in variable chunks: each chunk the records of `chunks`, point-
// wise; `vlr` (a whole VLR) appended to the header's; `tail` (which starts at the returned
// file's size at call time, `tail_at`) after the chunk table. The chunk offsets go to `starts`.
struct HandmadeLaz {
  std::vector<std::vector<std::size_t>> chunks;
  std::string vlr;
  std::string bytes;
  std::vector<std::size_t> starts;
  std::size_t tail_at = 0;
  void build(const std::string& las, const std::function<std::string(const HandmadeLaz&)>& tail = {}) {
    const std::size_t offset = get<std::uint32_t>(las, 96), record = get<std::uint16_t>(las, 105);
    laz::LaszipVlr lz;
    lz.version_major = 2;
    lz.version_minor = 2;
    lz.chunk_size = laz::kVariableChunks;
    lz.items = laz::pointwise_items(3, record - 34);
    const std::string body = lz.body();
    std::string lz_vlr(54, '\0');
    std::memcpy(lz_vlr.data() + 2, "laszip encoded", 14);
    put<std::uint16_t>(lz_vlr, 18, laz::kLaszipRecordId);
    put<std::uint16_t>(lz_vlr, 20, static_cast<std::uint16_t>(body.size()));
    lz_vlr += body + vlr;
    std::string header = las.substr(0, offset);  // simple.las has no VLR of its own
    put<std::uint32_t>(header, 100, vlr.empty() ? 1 : 2);
    put<std::uint32_t>(header, 96, static_cast<std::uint32_t>(offset + lz_vlr.size()));
    header[104] = static_cast<char>(header[104] | 0x80);
    std::vector<unsigned char> coded;
    laz::ChunkEncoder encoder(lz, coded);
    laz::ChunkTable table;
    bytes = header + lz_vlr + std::string(8, '\0');
    for (const auto& chunk : chunks) {
      const std::size_t before = coded.size();
      starts.push_back(bytes.size() + before);
      encoder.start();
      for (std::size_t i : chunk) encoder.add(las.data() + offset + i * record);
      encoder.finish();
      table.points.push_back(chunk.size());
      table.bytes.push_back(coded.size() - before);
    }
    bytes += std::string(coded.begin(), coded.end());
    put<std::int64_t>(bytes, header.size() + lz_vlr.size(), static_cast<std::int64_t>(bytes.size()));
    bytes += laz::encode_chunk_table(table, true);
    tail_at = bytes.size();
    if (tail) bytes += tail(*this);
  }
};

// Variable chunks (COPC files use them: one chunk per octree node): the chunk table gives each
// chunk's point count. simple.las's records in chunks of 700, 300 and 65 points.
TEST(Laz, VariableChunksAreReadByTheirTable) {
  HandmadeLaz file;
  file.chunks.resize(3);
  for (std::size_t i = 0; i < 1065; ++i) file.chunks[i < 700 ? 0 : i < 1000 ? 1 : 2].push_back(i);
  file.build(read_bytes(test::test_data_path("simple.las")));
  const auto path = write_bytes(temp("variable.laz"), file.bytes);
  const CloudReadResult read = read_point_cloud(path);
  EXPECT_TRUE(test::contains(read.encoding, "variable chunks")) << read.encoding;
  expect_same_clouds(read_point_cloud(test::test_data_path("simple.las")).cloud, read.cloud);
  std::filesystem::remove(path);
}

// COPC: an octree over simple.las (level 0: every tenth point; level 1: the rest by octant of the
// root cube), one chunk per node, the hierarchy page after the chunk table. Read by level and by
// bounds, decoding only the nodes asked for.
TEST(Laz, CopcIsReadByOctreeLevelAndBounds) {
  const std::string las_bytes = read_bytes(test::test_data_path("simple.las"));
  const PointCloud las = read_point_cloud(test::test_data_path("simple.las")).cloud;
  const BoundingBox box = bounding_box(las.positions);
  const Vector3d center = (box.min + box.max) / 2;
  const double halfsize = (box.max - box.min).maxCoeff() / 2 * 1.01;
  HandmadeLaz file;
  file.chunks.resize(9);
  std::vector<std::array<int, 4>> keys{{0, 0, 0, 0}};
  for (int o = 0; o < 8; ++o) keys.push_back({1, o & 1, (o >> 1) & 1, o >> 2});
  for (std::size_t i = 0; i < las.size(); ++i) {
    const Vector3d& p = las.positions[i];
    file.chunks[i % 10 == 0 ? 0 : 1 + (p.x() >= center.x()) + 2 * (p.y() >= center.y()) + 4 * (p.z() >= center.z())].push_back(i);
  }
  // The COPC info VLR: center, halfsize, spacing, then the root hierarchy page's offset and size.
  std::string info(160, '\0');
  for (int a = 0; a < 3; ++a) put<double>(info, 8 * a, center[a]);
  put<double>(info, 24, halfsize);
  std::string info_vlr(54, '\0');
  std::memcpy(info_vlr.data() + 2, "copc", 4);
  put<std::uint16_t>(info_vlr, 18, 1);
  put<std::uint16_t>(info_vlr, 20, 160);
  file.vlr = info_vlr + info;
  const std::size_t info_at = 227 + 54 + 34 + 6 * 3 + 54;  // header, LASzip VLR (3 items), VLR header
  file.build(las_bytes, [&](const HandmadeLaz& f) {
    std::string page(32 * keys.size(), '\0');
    for (std::size_t k = 0; k < keys.size(); ++k) {
      std::memcpy(page.data() + 32 * k, keys[k].data(), 16);
      put<std::uint64_t>(page, 32 * k + 16, f.starts[k]);
      put<std::int32_t>(page, 32 * k + 24, static_cast<std::int32_t>((k + 1 < f.starts.size() ? f.starts[k + 1] : f.tail_at) - f.starts[k]));
      put<std::int32_t>(page, 32 * k + 28, static_cast<std::int32_t>(f.chunks[k].size()));
    }
    return page;
  });
  put<std::uint64_t>(file.bytes, info_at + 40, file.tail_at);
  put<std::uint64_t>(file.bytes, info_at + 48, 32 * keys.size());
  const auto path = write_bytes(temp("octree.copc.laz"), file.bytes);

  ReadOptions options;
  EXPECT_EQ(read_point_cloud(path, options).cloud.size(), las.size());
  options.copc_level = 0;
  const CloudReadResult level0 = read_point_cloud(path, options);
  EXPECT_TRUE(test::contains(level0.encoding, "COPC octree: 1 of 9 nodes read")) << level0.encoding;
  ASSERT_EQ(level0.cloud.size(), file.chunks[0].size());
  for (std::size_t k = 0; k < level0.cloud.size(); ++k) ASSERT_EQ(level0.cloud.positions[k], las.positions[10 * k]);

  // Bounds: the low-x half; only the nodes meeting it are decoded, the points are those inside.
  options.copc_level = -1;
  options.bounds = std::array<double, 6>{box.min.x(), box.min.y(), box.min.z(), center.x() - 1.0, box.max.y(), box.max.z()};
  const CloudReadResult half = read_point_cloud(path, options);
  EXPECT_TRUE(test::contains(half.encoding, "COPC octree: 5 of 9 nodes read")) << half.encoding;
  std::size_t inside = 0;
  for (const Vector3d& p : las.positions) inside += p.x() <= center.x() - 1.0;
  EXPECT_EQ(half.cloud.size(), inside);
  for (const Vector3d& p : half.cloud.positions) ASSERT_LE(p.x(), center.x() - 1.0);

  // A level is a COPC option: refused for plain LAZ and for other formats.
  ReadOptions level;
  level.copc_level = 2;
  EXPECT_TRUE(test::contains(test::error_of<UsageError>([&] { (void)read_point_cloud(test::test_data_path("simple.laz"), level); }), "needs a COPC file"));
  EXPECT_TRUE(test::contains(test::error_of<UsageError>([&] { (void)read_point_cloud(test::test_data_path("simple.las"), level); }), "COPC (LAZ) option"));
  std::filesystem::remove(path);
}

TEST(Laz, ChunkTablesOfFixedAndVariableChunksRoundTrip) {
  laz::ChunkTable table;
  table.points = {50000, 50000, 123, 1, 7000000};
  table.bytes = {200000, 180000, 777, 40, 30000000};
  const std::string fixed = laz::encode_chunk_table(table, false);
  const std::string variable = laz::encode_chunk_table(table, true);
  const auto fixed_back = laz::decode_chunk_table(reinterpret_cast<const unsigned char*>(fixed.data()), fixed.size(), false);
  const auto variable_back = laz::decode_chunk_table(reinterpret_cast<const unsigned char*>(variable.data()), variable.size(), true);
  EXPECT_EQ(fixed_back.bytes, table.bytes);
  EXPECT_EQ(variable_back.bytes, table.bytes);
  EXPECT_EQ(variable_back.points, table.points);
}

PointCloud sample_cloud(std::size_t n, bool colours, bool normals) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud cloud;
  cloud.positions.resize(n);
  for (auto& p : cloud.positions) p = Vector3d(596000.0 + 100 * u(rng), 4830000.0 + 100 * u(rng), 20.0 + 5 * u(rng));
  for (auto& p : cloud.positions) p = (p * 1e4).array().round() / 1e4;  // on the 0.1 mm grid the writer uses
  if (colours) {
    cloud.colors.resize(n);
    for (auto& c : cloud.colors) c = Vector3f(float(rng() % 65536) / 65535.0f, float(rng() % 65536) / 65535.0f, float(rng() % 65536) / 65535.0f);
  }
  if (normals) {
    cloud.normals.resize(n);
    for (auto& v : cloud.normals) v = Vector3d(float(u(rng)), float(u(rng)), float(u(rng)));
  }
  auto& intensity = cloud.fields.add("intensity", n, ScalarType::UInt16).values;
  auto& ret = cloud.fields.add("return_number", n, ScalarType::UInt8).values;
  auto& rets = cloud.fields.add("number_of_returns", n, ScalarType::UInt8).values;
  auto& cls = cloud.fields.add("classification", n, ScalarType::UInt8).values;
  auto& time = cloud.fields.add("gps_time", n, ScalarType::Float64).values;
  auto& label = cloud.fields.add("label", n, ScalarType::Int32).values;
  for (std::size_t i = 0; i < n; ++i) {
    intensity[i] = rng() % 65536;
    rets[i] = 1 + rng() % 7;
    ret[i] = 1 + rng() % static_cast<unsigned>(rets[i]);
    cls[i] = rng() % 32;
    time[i] = 1e5 + 1e-5 * double(i);
    label[i] = static_cast<int>(rng() % 2000) - 1000;
  }
  return cloud;
}

TEST(Laz, CloudsRoundTripThroughSeveralChunks) {
  for (bool colours : {false, true}) {
    const PointCloud cloud = sample_cloud(120000, colours, !colours);
    const auto path = temp("cloud.laz");
    write_point_cloud(path, cloud);
    // Positions are quantised as LAS quantises them: the LAZ file reads back as the LAS file does.
    const auto las = temp("cloud.las");
    write_point_cloud(las, cloud);
    expect_same_clouds(read_point_cloud(las).cloud, read_point_cloud(path).cloud);
    std::filesystem::remove(las);
    // A record of 20 + 8 (+ 6) bytes and 4 or 12 extra bytes; LAZ should be well below that.
    const double las_size = double(cloud.size()) * (colours ? 38 : 40);
    EXPECT_LT(double(std::filesystem::file_size(path)), 0.8 * las_size);
    std::filesystem::remove(path);
  }
}

TEST(Laz, EmptyCloudRoundTrips) {
  const auto path = temp("empty.laz");
  write_point_cloud(path, PointCloud());
  EXPECT_EQ(read_point_cloud(path).cloud.size(), 0u);
  std::filesystem::remove(path);
}

// Bad input: each corruption refused with the file and the place, never a crash.
class LazCorruption : public ::testing::Test {
protected:
  void SetUp() override {
    write_point_cloud(good_, sample_cloud(120000, true, false));
    bytes_ = read_bytes(good_);
    points_ = get<std::uint32_t>(bytes_, 96);
    table_ = static_cast<std::size_t>(get<std::int64_t>(bytes_, points_));
    // The LASzip VLR follows the extra bytes VLR (the "label" field) after the 375-byte header.
    vlr_ = 375 + 54 + get<std::uint16_t>(bytes_, 375 + 20);
    ASSERT_EQ(bytes_.substr(vlr_ + 2, 14), "laszip encoded");
  }
  void TearDown() override {
    std::filesystem::remove(good_);
    std::filesystem::remove(bad_);
  }
  std::string error_of(const std::string& bytes) {
    write_bytes(bad_, bytes);
    return test::error_of<InputError>([&] { (void)read_point_cloud(bad_); });
  }
  std::filesystem::path good_ = temp("good.laz"), bad_ = temp("bad.laz");
  std::string bytes_;
  std::size_t points_ = 0, table_ = 0, vlr_ = 0;
};

TEST_F(LazCorruption, TruncatedFileNamesTheChunkTable) {
  const std::string message = error_of(bytes_.substr(0, bytes_.size() / 2));
  EXPECT_TRUE(test::contains(message, "bad.laz")) << message;
  EXPECT_TRUE(test::contains(message, "chunk table")) << message;
}

TEST_F(LazCorruption, WrongChunkTableNamesTheChunk) {
  std::string b = bytes_;
  // The second chunk's size as coded in the table cannot be edited in place; swap the table for
  // one that gives the first chunk too few bytes.
  laz::ChunkTable table = laz::decode_chunk_table(reinterpret_cast<const unsigned char*>(b.data() + table_), b.size() - table_, false);
  ASSERT_EQ(table.bytes.size(), 3u);
  table.bytes[0] -= 200;
  table.bytes[1] += 200;
  b = b.substr(0, table_) + laz::encode_chunk_table(table, false);
  const std::string message = error_of(b);
  EXPECT_TRUE(test::contains(message, "bad.laz: chunk 0 of 3")) << message;
}

TEST_F(LazCorruption, PointCountBeyondWhatTheChunksCanHoldIsRefusedBeforeAllocating) {
  std::string b = bytes_;
  put<std::uint64_t>(b, 247, std::uint64_t(1) << 40);  // LAS 1.4's 64-bit point count
  put<std::uint32_t>(b, vlr_ + 54 + 12, 0xFFFFFFF0u);  // the LASzip VLR's chunk size
  const std::string message = error_of(b);
  EXPECT_TRUE(test::contains(message, "points cannot fit in its")) << message;
}

TEST_F(LazCorruption, ChunkTableBeyondTheFileIsRefused) {
  std::string b = bytes_;
  put<std::int64_t>(b, points_, static_cast<std::int64_t>(b.size() + 100));
  const std::string message = error_of(b);
  EXPECT_TRUE(test::contains(message, "chunk table offset")) << message;
}

TEST_F(LazCorruption, GarbledChunkIsRefusedOrDecodedWithoutCrashing) {
  // Noise in the middle of chunk 1: the decoder must stay inside the chunk whatever it decodes.
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    std::string b = bytes_;
    const std::size_t at = points_ + 8 + (table_ - points_ - 8) / 2 + trial * 37;
    for (int k = 0; k < 64; ++k) b[at + k] = static_cast<char>(rng());
    write_bytes(bad_, b);
    try {
      (void)read_point_cloud(bad_);
    } catch (const InputError& e) {
      EXPECT_TRUE(test::contains(e.what(), "chunk")) << e.what();
    }
  }
}

TEST_F(LazCorruption, UnknownCompressorOrItemVersionIsRefused) {
  const std::size_t body = vlr_ + 54;
  std::string b = bytes_;
  put<std::uint16_t>(b, body, 9);
  std::string message = error_of(b);
  EXPECT_TRUE(test::contains(message, "LASzip VLR: LASzip compressor 9 is not supported")) << message;
  b = bytes_;
  put<std::uint16_t>(b, body + 34 + 4, 7);  // the first item's version
  message = error_of(b);
  EXPECT_TRUE(test::contains(message, "version 7 is not supported")) << message;
}

TEST_F(LazCorruption, MissingLaszipVlrIsRefused) {
  std::string b = bytes_;
  std::memcpy(b.data() + vlr_ + 2, "not laszip    ", 14);
  const std::string message = error_of(b);
  EXPECT_TRUE(test::contains(message, "without the LASzip VLR")) << message;
}

}  // namespace
}  // namespace pointsurf
