// SPDX-License-Identifier: GPL-3.0-or-later
// LAZ bench runner for bench/io/run_laz_bench.sh.
//   laz_runner generate N out.laz out.las   synthetic airborne scan of N points (seeded), written
//                                            as LAZ (timed: encode) and as LAS (for the ratio)
//   laz_runner decode in.laz                 decode every point record (timed), then the whole
//                                            read into a cloud (timed)
// Prints one JSON object per call.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "io/detail/las_format.h"
#include "io/detail/laz_items.h"
#include "pointsurf/io/io.h"

using namespace pointsurf;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Scan lines of an airborne sweep over rolling terrain: 1 cm steps along a line, 0.5 m between
// lines, a pulse every 10 microseconds, 1-3 returns, intensity and class varying slowly.
PointCloud airborne(std::size_t n) {
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(0.0, 0.02);
  PointCloud cloud;
  cloud.positions.resize(n);
  auto& intensity = cloud.fields.add("intensity", n, ScalarType::UInt16).values;
  auto& ret = cloud.fields.add("return_number", n, ScalarType::UInt8).values;
  auto& rets = cloud.fields.add("number_of_returns", n, ScalarType::UInt8).values;
  auto& cls = cloud.fields.add("classification", n, ScalarType::UInt8).values;
  auto& time = cloud.fields.add("gps_time", n, ScalarType::Float64).values;
  const std::size_t per_line = 20000;
  std::size_t i = 0;
  for (std::size_t pulse = 0; i < n; ++pulse) {
    const double x = 500000.0 + 0.05 * double(pulse % per_line);
    const double y = 5400000.0 + 0.5 * double(pulse / per_line);
    const double ground = 300.0 + 5.0 * std::sin(x * 0.01) * std::cos(y * 0.013);
    const int returns = rng() % 10 == 0 ? 1 + int(rng() % 3) : 1;
    for (int r = 1; r <= returns && i < n; ++r, ++i) {
      const double height = r == returns ? 0.0 : 2.0 + 10.0 * double(rng() % 100) / 100.0;
      cloud.positions[i] = Vector3d(x + noise(rng), y + noise(rng), ground + height + noise(rng));
      cloud.positions[i] = (cloud.positions[i] * 100.0).array().round() / 100.0;
      intensity[i] = 200 + double(rng() % 50) + 100.0 * (r == returns);
      ret[i] = r;
      rets[i] = returns;
      cls[i] = r == returns ? 2 : 5;
      time[i] = 250000.0 + 1e-5 * double(pulse);
    }
  }
  return cloud;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "generate" && argc == 5) {
    const PointCloud cloud = airborne(std::stoul(argv[2]));
    WriteOptions options;
    options.las_scale = 0.01;
    auto t = Clock::now();
    write_point_cloud(argv[3], cloud, options);
    const double encode = seconds_since(t);
    write_point_cloud(argv[4], cloud, options);
    fmt::print("{{\"points\": {}, \"encode_s\": {}, \"laz_bytes\": {}, \"las_bytes\": {}}}\n", cloud.size(), encode,
               std::filesystem::file_size(argv[3]), std::filesystem::file_size(argv[4]));
    return 0;
  }
  if (mode == "decode" && argc == 3) {
    // The records alone, as laz-perf's getPoint loop does: file bytes to point records.
    std::ifstream in(argv[2], std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto header = io::detail::parse_las_header(bytes, bytes.size(), argv[2]);
    io::detail::laz::LaszipVlr vlr;
    for (const auto& v : io::detail::las_vlrs(bytes, header))
      if (v.user_id == io::detail::laz::kLaszipUserId) vlr = io::detail::laz::LaszipVlr::parse(v.body);
    std::int64_t table_at = 0;
    std::memcpy(&table_at, bytes.data() + header.point_offset, 8);
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
    auto t = Clock::now();
    const auto table = io::detail::laz::decode_chunk_table(data + table_at, bytes.size() - table_at, false);
    io::detail::laz::ChunkDecoder decoder(vlr);
    std::vector<char> record(header.record_length);
    std::size_t at = header.point_offset + 8, done = 0;
    unsigned checksum = 0;
    for (std::size_t c = 0; c < table.bytes.size(); ++c) {
      decoder.start(data + at, table.bytes[c]);
      const std::size_t count = std::min<std::size_t>(vlr.chunk_size, header.count - done);
      for (std::size_t i = 0; i < count; ++i) {
        if (!decoder.next(record.data())) return 2;
        checksum += static_cast<unsigned char>(record[0]);
      }
      done += count;
      at += table.bytes[c];
    }
    const double records = seconds_since(t);
    t = Clock::now();
    const CloudReadResult read = read_point_cloud(argv[2]);
    const double full = seconds_since(t);
    fmt::print("{{\"points\": {}, \"decode_records_s\": {}, \"read_cloud_s\": {}, \"checksum\": {}}}\n", read.cloud.size(), records, full, checksum);
    return 0;
  }
  std::fprintf(stderr, "usage: laz_runner generate N out.laz out.las | laz_runner decode in.laz\n");
  return 1;
}
