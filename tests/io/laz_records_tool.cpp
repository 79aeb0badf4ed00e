// SPDX-License-Identifier: GPL-3.0-or-later
// Test helper for tests/io/lazperf_check.sh: writes LAZ files of point formats that `convert`
// does not write (0-3, 8; several scanner channels in 6-8), with seeded random records, and the
// same records uncompressed as LAS, so that another decoder can be compared with the records
// themselves.
//   laz_records_tool FORMAT POINTS CHANNELS out.laz out.las
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "io/detail/laz_items.h"
#include "io/detail/laz_layered.h"

namespace laz = pointsurf::io::detail::laz;

namespace {

template <typename T>
void put(std::string& s, std::size_t at, T v) {
  std::memcpy(s.data() + at, &v, sizeof(T));
}

void save(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: laz_records_tool FORMAT POINTS CHANNELS out.laz out.las\n");
    return 1;
  }
  const int format = std::stoi(argv[1]);
  const std::size_t n = std::stoul(argv[2]);
  const int channels = std::stoi(argv[3]);
  const bool extended = format >= 6;
  laz::LaszipVlr vlr;
  vlr.compressor = extended ? 3 : 2;
  vlr.items = extended ? laz::layered_items(format, 2) : laz::pointwise_items(format, 2);
  const std::size_t record = vlr.record_size();

  std::mt19937 rng(static_cast<unsigned>(format * 100 + channels));
  std::string records(n * record, '\0');
  std::int32_t x = 0, y = 0, z = 1000;
  double t = 300000.0;
  unsigned channel = 0;
  for (std::size_t i = 0; i < n; ++i) {
    char* r = records.data() + i * record;
    x += static_cast<std::int32_t>(rng() % 200) - 90;
    y += static_cast<std::int32_t>(rng() % 30) - 15;
    z += static_cast<std::int32_t>(rng() % 41) - 20;
    std::memcpy(r, &x, 4);
    std::memcpy(r + 4, &y, 4);
    std::memcpy(r + 8, &z, 4);
    const auto intensity = static_cast<std::uint16_t>(300 + rng() % 200);
    std::memcpy(r + 12, &intensity, 2);
    if (rng() % 3) t += 1e-5;
    std::size_t at;
    if (extended) {
      const unsigned rets = 1 + rng() % 3, ret = 1 + rng() % rets;
      r[14] = static_cast<char>(ret | (rets << 4));
      if (channels > 1 && rng() % 100 == 0) channel = rng() % static_cast<unsigned>(channels);
      r[15] = static_cast<char>((channel << 4) | ((rng() % 50 == 0) << 6));
      r[16] = static_cast<char>(rng() % 5 ? 2 : 6);
      r[17] = static_cast<char>(rng() % 20 ? 0 : 7);
      const auto angle = static_cast<std::int16_t>(static_cast<int>(rng() % 5000) - 2500);
      std::memcpy(r + 18, &angle, 2);
      const auto source = static_cast<std::uint16_t>(17 + channel);
      std::memcpy(r + 20, &source, 2);
      std::memcpy(r + 22, &t, 8);
      at = 30;
      if (format == 7 || format == 8) {
        for (int c = 0; c < (format == 8 ? 4 : 3); ++c) {
          const auto v = static_cast<std::uint16_t>(rng() % 65536);
          std::memcpy(r + at + 2 * c, &v, 2);
        }
        at += format == 8 ? 8 : 6;
      }
    } else {
      const unsigned rets = 1 + rng() % 3, ret = 1 + rng() % rets;
      r[14] = static_cast<char>(ret | (rets << 3) | ((rng() % 50 == 0) << 6));
      r[15] = static_cast<char>(rng() % 5 ? 2 : 6);
      r[16] = static_cast<char>(static_cast<int>(rng() % 61) - 30);
      r[17] = static_cast<char>(rng() % 20 ? 0 : 7);
      const auto source = static_cast<std::uint16_t>(17);
      std::memcpy(r + 18, &source, 2);
      at = 20;
      if (format == 1 || format == 3) {
        std::memcpy(r + at, &t, 8);
        at += 8;
      }
      if (format == 2 || format == 3) {
        for (int c = 0; c < 3; ++c) {
          const auto v = static_cast<std::uint16_t>(rng() % 65536);
          std::memcpy(r + at + 2 * c, &v, 2);
        }
        at += 6;
      }
    }
    r[at] = static_cast<char>(rng());
    r[at + 1] = static_cast<char>(i / 100);
  }

  // LAS 1.4 header: scale 0.01, offset 0; an extra bytes VLR for the 2 trailing bytes (two
  // unsigned chars) so that readers name them.
  std::string evlr(54 + 2 * 192, '\0');
  std::memcpy(evlr.data() + 2, "LASF_Spec", 9);
  put<std::uint16_t>(evlr, 18, 4);
  put<std::uint16_t>(evlr, 20, 2 * 192);
  for (int e = 0; e < 2; ++e) {
    evlr[54 + 192 * e + 2] = 1;  // unsigned char
    std::memcpy(evlr.data() + 54 + 192 * e + 4, e ? "second" : "first", e ? 6 : 5);
  }
  const std::string body = vlr.body();
  std::string zvlr(54, '\0');
  std::memcpy(zvlr.data() + 2, laz::kLaszipUserId, 14);
  put<std::uint16_t>(zvlr, 18, laz::kLaszipRecordId);
  put<std::uint16_t>(zvlr, 20, static_cast<std::uint16_t>(body.size()));
  zvlr += body;
  auto header = [&](bool compressed) {
    std::string h(375, '\0');
    std::memcpy(h.data(), "LASF", 4);
    h[24] = 1;
    h[25] = 4;
    put<std::uint16_t>(h, 94, 375);
    put<std::uint32_t>(h, 96, static_cast<std::uint32_t>(375 + evlr.size() + (compressed ? zvlr.size() : 0)));
    put<std::uint32_t>(h, 100, compressed ? 2 : 1);
    h[104] = static_cast<char>(format | (compressed ? 0x80 : 0));
    put<std::uint16_t>(h, 105, static_cast<std::uint16_t>(record));
    if (!extended) put<std::uint32_t>(h, 107, static_cast<std::uint32_t>(n));
    for (int a = 0; a < 3; ++a) put<double>(h, 131 + 8 * a, 0.01);
    put<std::uint64_t>(h, 247, n);
    return h + evlr + (compressed ? zvlr : std::string());
  };
  save(argv[5], header(false) + records);

  std::string file = header(true);
  const std::size_t table_slot = file.size();
  file += std::string(8, '\0');
  std::vector<unsigned char> chunk;
  laz::ChunkEncoder encoder(vlr, chunk);
  laz::ChunkTable table;
  for (std::size_t first = 0; first < n; first += vlr.chunk_size) {
    chunk.clear();
    encoder.start();
    for (std::size_t i = first; i < std::min<std::size_t>(n, first + vlr.chunk_size); ++i) encoder.add(records.data() + i * record);
    encoder.finish();
    file.append(reinterpret_cast<const char*>(chunk.data()), chunk.size());
    table.bytes.push_back(chunk.size());
  }
  put<std::int64_t>(file, table_slot, static_cast<std::int64_t>(file.size()));
  file += laz::encode_chunk_table(table, false);
  save(argv[4], file);
  return 0;
}
