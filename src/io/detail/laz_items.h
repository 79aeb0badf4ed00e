// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// LASzip's item coders and the LASzip VLR: what a LAZ point record is made of and how each part
// is predicted from the previous point of the chunk.
//
// Point-wise (compressor 2, item version 2) for point formats 0-5: POINT10 (x, y, z by
// streaming medians of the differences per return context, intensity, the flag byte,
// classification, scan angle, user data, point source), GPSTIME11, RGB12 and BYTE (extra
// bytes). Each chunk starts with one raw record, then an arithmetic-coded stream.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "io/detail/laz_codec.h"

namespace pointsurf::io::detail::laz {

enum ItemType : std::uint16_t { kByte = 0, kPoint10 = 6, kGpsTime11 = 7, kRgb12 = 8, kWavePacket13 = 9, kPoint14 = 10, kRgb14 = 11, kRgbNir14 = 12,
                                kWavePacket14 = 13, kByte14 = 14 };

struct Item {
  std::uint16_t type = 0, size = 0, version = 0;
};

/// The "laszip encoded" / 22204 VLR.
struct LaszipVlr {
  std::uint16_t compressor = 2;  // 0 none, 1 point-wise, 2 point-wise chunked, 3 layered chunked
  std::uint16_t coder = 0;       // 0 arithmetic
  std::uint8_t version_major = 3, version_minor = 4;
  std::uint16_t revision = 3;
  std::uint32_t options = 0;
  std::uint32_t chunk_size = 50000;  // points per chunk; 0xFFFFFFFF: variable chunks
  std::vector<Item> items;

  std::size_t record_size() const;
  /// The VLR body; `parse` throws std::runtime_error with a reason.
  std::string body() const;
  static LaszipVlr parse(std::string_view body);
};

inline constexpr char kLaszipUserId[] = "laszip encoded";
inline constexpr std::uint16_t kLaszipRecordId = 22204;
inline constexpr std::uint32_t kVariableChunks = 0xFFFFFFFFu;

/// The items LASzip writes for a point format (0-5) with `extra` extra bytes per record.
std::vector<Item> pointwise_items(int format, std::size_t extra);

class ItemCoder;
class LayeredDecoder;
class LayeredEncoder;

/// Decodes the records of one chunk at a time.
class ChunkDecoder {
public:
  /// Throws std::runtime_error for items or versions it cannot decode.
  explicit ChunkDecoder(const LaszipVlr& vlr);
  ~ChunkDecoder();
  /// Starts a chunk of `size` bytes.
  void start(const unsigned char* data, std::size_t size);
  /// Decodes the next record into `record` (record_size() bytes). False if the chunk's bytes ran
  /// out (a truncated or corrupt chunk).
  bool next(char* record);
  std::size_t record_size() const { return record_size_; }

private:
  std::vector<std::unique_ptr<ItemCoder>> coders_;
  std::unique_ptr<LayeredDecoder> layered_;  // compressor 3
  std::size_t record_size_ = 0;
  Decoder dec_;
  const unsigned char* data_ = nullptr;
  std::size_t size_ = 0;
  bool first_ = true;
};

/// Encodes records into chunks appended to a byte vector.
class ChunkEncoder {
public:
  ChunkEncoder(const LaszipVlr& vlr, std::vector<unsigned char>& out);
  ~ChunkEncoder();
  void start();
  void add(const char* record);
  void finish();

private:
  std::vector<std::unique_ptr<ItemCoder>> coders_;
  std::unique_ptr<LayeredEncoder> layered_;  // compressor 3
  std::vector<unsigned char>& out_;
  Encoder enc_;
  bool first_ = true;
};

/// The chunk table: points and bytes per chunk, coded as LASzip does.
struct ChunkTable {
  std::vector<std::uint64_t> points, bytes;
};
std::string encode_chunk_table(const ChunkTable& table, bool variable);
/// Throws std::runtime_error when the table is malformed.
ChunkTable decode_chunk_table(const unsigned char* data, std::size_t size, bool variable);

}  // namespace pointsurf::io::detail::laz
