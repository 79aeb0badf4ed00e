// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// E57 (ASTM E2807-11), shared by the reader (e57_read.cpp) and the writer (e57_write.cpp):
// section and packet constants, the namespaces of the extensions pointsurf reads and writes,
// and the reader over bytes already in memory (the fuzz target and the tests of corrupted files;
// read_e57 maps the file and calls it).
//
// Layout: a 48-byte header, then 1024-byte pages with a CRC-32C each (io/detail/e57_pages.h).
// The XML section describes the data: /data3D holds one structure per scan with its pose and
// a CompressedVector `points` whose prototype lists the fields of a point; the values live in
// a binary section of data packets, each carrying one slice of every field's bytestream.
// Integer and ScaledInteger fields are bit-packed (value - minimum in ceil(log2(max-min+1))
// bits, least significant bit first, a continuous stream across packets); Float fields are raw
// little-endian float32 or float64.
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "io/detail/formats.h"

namespace pointsurf::io::detail {

static_assert(std::endian::native == std::endian::little, "the E57 code assumes a little-endian host");

inline constexpr std::size_t kSectionHeaderSize = 32;
inline constexpr std::uint8_t kCompressedVectorSection = 1;
inline constexpr std::uint8_t kIndexPacket = 0, kDataPacket = 1, kEmptyPacket = 2;
inline constexpr std::size_t kMaxPacketSize = 65536;
inline constexpr const char* kE57Namespace = "http://www.astm.org/COMMIT/E57/2010-e57-v1.0";
inline constexpr const char* kNormalsNamespace = "http://www.libe57.org/E57_NOR_surface_normals.txt";
inline constexpr const char* kPointsurfNamespace = "https://pointsurf.org/e57-fields";
inline constexpr std::string_view kPointsurfPrefix = "pointsurf:";

/// Bits of a bit-packed integer field with values in [minimum, maximum].
inline unsigned bits_for_range(std::int64_t minimum, std::int64_t maximum) {
  const std::uint64_t range = static_cast<std::uint64_t>(maximum) - static_cast<std::uint64_t>(minimum);
  return range == 0 ? 0u : static_cast<unsigned>(64 - std::countl_zero(range));
}

/// Reads an E57 file held in `bytes`; `name` is used in messages. Throws InputError on any
/// malformed input, naming the page, section, scan or field.
RawData read_e57_bytes(std::string_view bytes, const std::string& name, const ReadOptions& options);

}  // namespace pointsurf::io::detail
