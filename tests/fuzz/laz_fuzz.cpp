// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer target for the LAZ decoders: arbitrary bytes as a chunk of point records (the first
// byte picks the compressor, point-wise for formats 0-5 or layered for 6-10, the format and the
// extra bytes) and as a chunk table. The decoder must
// stay inside its input and stop within the points asked for, whatever the bytes. The records it
// decodes are then encoded and decoded again: they must come back bit for bit (the encoders run
// under the sanitizers too, on arbitrary records).
// Built with -DPOINTSURF_BUILD_FUZZERS=ON (clang); run e.g.
//   build-fuzz/laz_fuzz -max_total_time=300 -max_len=4096 corpus/
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "io/detail/laz_items.h"
#include "io/detail/laz_layered.h"

namespace laz = pointsurf::io::detail::laz;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const int format = (data[0] & 3) + 2 * (data[0] >> 7);  // 0-5
  const std::size_t extra = (data[0] >> 2) & 15;
  const bool variable = (data[0] & 1) != 0;
  try {
    laz::ChunkTable table = laz::decode_chunk_table(data + 1, size - 1, variable);
    (void)table;
  } catch (const std::runtime_error&) {
  }
  laz::LaszipVlr vlr;
  if (data[0] & 0x40) {
    vlr.compressor = 3;
    vlr.items = laz::layered_items(6 + format % 5, extra);
  } else {
    vlr.items = laz::pointwise_items(format, extra);
  }
  laz::ChunkDecoder decoder(vlr);
  decoder.start(data + 1, size - 1);
  const std::size_t size_of_record = vlr.record_size();
  std::vector<char> records;
  std::vector<char> record(size_of_record);
  try {
    for (int i = 0; i < 2000; ++i) {
      if (!decoder.next(record.data())) break;
      records.insert(records.end(), record.begin(), record.end());
    }
  } catch (const std::runtime_error&) {
  }
  const std::size_t n = records.size() / size_of_record;
  if (n == 0) return 0;
  std::vector<unsigned char> coded;
  laz::ChunkEncoder encoder(vlr, coded);
  encoder.start();
  for (std::size_t i = 0; i < n; ++i) encoder.add(records.data() + i * size_of_record);
  encoder.finish();
  laz::ChunkDecoder again(vlr);
  again.start(coded.data(), coded.size());
  for (std::size_t i = 0; i < n; ++i)
    if (!again.next(record.data()) || std::memcmp(record.data(), records.data() + i * size_of_record, size_of_record) != 0) __builtin_trap();
  return 0;
}
