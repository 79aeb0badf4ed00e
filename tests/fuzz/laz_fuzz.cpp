// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer target for the LAZ decoders: arbitrary bytes as a chunk of point records (the first
// byte picks the compressor, point-wise for formats 0-3 or layered for 6-8, the format and the
// extra bytes) and as a chunk table. The decoder must
// stay inside its input and stop within the points asked for, whatever the bytes.
// Built with -DPOINTSURF_BUILD_FUZZERS=ON (clang); run e.g.
//   build-fuzz/laz_fuzz -max_total_time=300 -max_len=4096 corpus/
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "io/detail/laz_items.h"
#include "io/detail/laz_layered.h"

namespace laz = pointsurf::io::detail::laz;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const int format = data[0] & 3;
  const std::size_t extra = (data[0] >> 2) & 15;
  const bool variable = (data[0] & 0x80) != 0;
  try {
    laz::ChunkTable table = laz::decode_chunk_table(data + 1, size - 1, variable);
    (void)table;
  } catch (const std::runtime_error&) {
  }
  laz::LaszipVlr vlr;
  if (data[0] & 0x40) {
    vlr.compressor = 3;
    vlr.items = laz::layered_items(6 + format % 3, extra);
  } else {
    vlr.items = laz::pointwise_items(format, extra);
  }
  laz::ChunkDecoder decoder(vlr);
  decoder.start(data + 1, size - 1);
  std::vector<char> record(vlr.record_size());
  try {
    for (int i = 0; i < 2000; ++i)
      if (!decoder.next(record.data())) break;
  } catch (const std::runtime_error&) {
  }
  return 0;
}
