// SPDX-License-Identifier: GPL-3.0-or-later
// LAZ (LASzip-compressed LAS) reader and writer. The header, VLRs and point records are LAS's
// (las_format.cpp); the point data is a sequence of chunks, each decoded on its own by the
// LASzip item coders (detail/laz_items.cpp), followed by a chunk table of their sizes. The file
// is read chunk by chunk: memory holds one chunk's bytes besides the cloud.
#include <algorithm>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "io/detail/las_format.h"
#include "io/detail/laz_items.h"
#include "io/detail/laz_layered.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

// Positioned reads from a file; every failure is an InputError naming it.
class InputFile {
public:
  InputFile(const std::filesystem::path& path, std::string name) : name_(std::move(name)) {
    file_ = std::fopen(path.c_str(), "rb");
    if (!file_) throw InputError(fmt::format("{}: cannot open for reading", name_));
    std::error_code ec;
    size_ = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(fmt::format("{}: cannot read its size", name_));
  }
  ~InputFile() { std::fclose(file_); }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  std::uint64_t size() const { return size_; }
  // `count` bytes at `offset`; false when the file ends first.
  bool read(std::uint64_t offset, std::size_t count, void* out) {
    if (offset > size_ || count > size_ - offset) return false;
    if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) return false;
    return std::fread(out, 1, count, file_) == count;
  }
  std::string read(std::uint64_t offset, std::size_t count) {
    std::string s(count, '\0');
    if (!read(offset, count, s.data())) throw InputError(fmt::format("{}: file ends before byte {}", name_, offset + count));
    return s;
  }

private:
  std::string name_;
  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0;
};

std::string describe(const laz::LaszipVlr& v) {
  static const char* const kCompressors[] = {"none", "point-wise", "point-wise chunked", "layered chunked"};
  return fmt::format("LASzip {}.{}r{}, {} compressor, {}", v.version_major, v.version_minor, v.revision,
                     v.compressor < 4 ? kCompressors[v.compressor] : "unknown",
                     v.chunk_size == laz::kVariableChunks ? std::string("variable chunks") : fmt::format("chunk size {}", v.chunk_size));
}

}  // namespace

RawData read_laz(const std::filesystem::path& path, const ReadOptions&) {
  const std::string name = display_name(path);
  InputFile file(path, name);
  const std::uint64_t file_size = file.size();
  std::string head = file.read(0, static_cast<std::size_t>(std::min<std::uint64_t>(file_size, 375)));
  LasHeader header = parse_las_header(head, file_size, name);
  if (header.point_offset > file_size)
    throw InputError(fmt::format("{}: offset to point data {} lies beyond the file's {} bytes", name, header.point_offset, file_size));
  head = file.read(0, header.point_offset);
  header = parse_las_header(head, file_size, name);

  const std::vector<LasVlr> vlrs = las_vlrs(head, header);
  const auto found = std::find_if(vlrs.begin(), vlrs.end(), [](const LasVlr& v) {
    return v.user_id == laz::kLaszipUserId && v.record_id == laz::kLaszipRecordId;
  });
  if (found == vlrs.end())
    throw InputError(fmt::format("{}: compressed point data without the LASzip VLR ('{}', record {}) that describes it", name,
                                 laz::kLaszipUserId, laz::kLaszipRecordId));
  laz::LaszipVlr lz;
  std::unique_ptr<laz::ChunkDecoder> decoder;
  try {
    lz = laz::LaszipVlr::parse(found->body);
    decoder = std::make_unique<laz::ChunkDecoder>(lz);
  } catch (const std::runtime_error& e) {
    throw InputError(fmt::format("{}: LASzip VLR: {}", name, e.what()));
  }
  if (lz.record_size() != header.record_length)
    throw InputError(fmt::format("{}: the LASzip items make {}-byte records, the header says {}", name, lz.record_size(), header.record_length));
  if (lz.chunk_size == 0) throw InputError(fmt::format("{}: LASzip VLR: chunk size 0", name));

  // Where each chunk starts and how many points it holds.
  const std::uint64_t n = header.count;
  std::vector<std::uint64_t> chunk_start, chunk_bytes, chunk_points;
  if (lz.compressor == 1) {
    chunk_start.push_back(header.point_offset);
    chunk_bytes.push_back(file_size - header.point_offset);
    chunk_points.push_back(n);
  } else {
    std::int64_t table_at = 0;
    if (!file.read(header.point_offset, 8, &table_at))
      throw InputError(fmt::format("{}: file ends at byte {} before the chunk table offset at byte {}", name, file_size, header.point_offset));
    const std::uint64_t first = header.point_offset + 8;
    if (table_at == -1 && file_size >= first + 8) file.read(file_size - 8, 8, &table_at);  // written last by a streaming writer
    if (table_at < static_cast<std::int64_t>(first) || static_cast<std::uint64_t>(table_at) + 8 > file_size)
      throw InputError(fmt::format("{}: chunk table offset {} (byte {}) lies outside the file ({} bytes): truncated or corrupt", name,
                                   table_at, header.point_offset, file_size));
    const std::size_t table_size = static_cast<std::size_t>(std::min<std::uint64_t>(file_size - table_at, std::uint64_t(64) << 20));
    const std::string table_bytes = file.read(static_cast<std::uint64_t>(table_at), table_size);
    const bool variable = lz.chunk_size == laz::kVariableChunks;
    laz::ChunkTable table;
    try {
      table = laz::decode_chunk_table(reinterpret_cast<const unsigned char*>(table_bytes.data()), table_bytes.size(), variable);
    } catch (const std::runtime_error& e) {
      throw InputError(fmt::format("{}: chunk table at byte {}: {}", name, table_at, e.what()));
    }
    std::uint64_t at = first, points = 0;
    for (std::size_t c = 0; c < table.bytes.size() && points < n; ++c) {
      const std::uint64_t count = variable ? table.points[c] : std::min<std::uint64_t>(lz.chunk_size, n - points);
      if (at + table.bytes[c] > static_cast<std::uint64_t>(table_at))
        throw InputError(fmt::format("{}: chunk {} of {}: the chunk table gives it {} bytes from byte {}, past the chunk table at byte {}", name,
                                     c, table.bytes.size(), table.bytes[c], at, table_at));
      chunk_start.push_back(at);
      chunk_bytes.push_back(table.bytes[c]);
      chunk_points.push_back(count);
      at += table.bytes[c];
      points += count;
    }
    if (points < n)
      throw InputError(fmt::format("{}: the chunk table's {} chunks hold {} points; the header announces {}", name, table.bytes.size(), points, n));
  }

  RawData raw;
  raw.encoding = fmt::format("LAZ {}.{} point format {} ({})", header.major, header.minor, header.format, describe(lz));
  LasRecordReader records(header, head, name, raw);
  std::vector<char> record(header.record_length);
  std::vector<unsigned char> chunk;
  std::uint64_t i = 0;
  for (std::size_t c = 0; c < chunk_start.size() && i < n; ++c) {
    const std::uint64_t first = i;
    const auto fail = [&](std::string_view what) {
      return InputError(fmt::format("{}: chunk {} of {} (points {} to {}, {} bytes at byte {}): {}", name, c, chunk_start.size(), first,
                                    first + chunk_points[c] - 1, chunk_bytes[c], chunk_start[c], what));
    };
    chunk.resize(static_cast<std::size_t>(chunk_bytes[c]));
    if (!file.read(chunk_start[c], chunk.size(), chunk.data())) throw fail(fmt::format("file ends at byte {}", file_size));
    decoder->start(chunk.data(), chunk.size());
    const std::uint64_t end = std::min(n, i + chunk_points[c]);
    bool intact = true;
    try {
      for (; i < end && (intact = decoder->next(record.data())); ++i) records.read(static_cast<std::size_t>(i), record.data());
    } catch (const std::runtime_error& e) {  // from the decoder: what it found corrupt
      throw fail(fmt::format("corrupt: {}", e.what()));
    }
    if (!intact) throw fail(fmt::format("truncated or corrupt: the compressed data ends at point {}", i));
  }
  records.finish();
  return raw;
}

// Written as the LAS writer writes (LAS 1.4, point format 6, or 7 with colours, extra bytes for
// the other fields) with LASzip's layered chunked compressor, 50,000 points per chunk.
void write_laz(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options) {
  const std::string name = display_name(path);
  const LasRecordWriter writer(cloud, options, name);
  laz::LaszipVlr lz;
  lz.compressor = 3;
  lz.items = laz::layered_items(writer.format(), writer.extra_bytes());
  const std::string head = writer.head(las_vlr(laz::kLaszipUserId, laz::kLaszipRecordId, "pointsurf", lz.body()), 1, 0x80);

  FileWriter out(path);
  out.write(head);
  out.write_value<std::int64_t>(0);  // the chunk table's offset, patched below
  std::uint64_t at = head.size() + 8;
  std::vector<unsigned char> chunk;
  laz::ChunkEncoder encoder(lz, chunk);
  laz::ChunkTable table;
  std::vector<char> record(writer.record_length());
  const std::size_t n = cloud.size();
  for (std::size_t first = 0; first < n; first += lz.chunk_size) {
    const std::size_t last = std::min<std::size_t>(n, first + lz.chunk_size);
    chunk.clear();
    encoder.start();
    for (std::size_t i = first; i < last; ++i) {
      writer.record(i, record.data());
      encoder.add(record.data());
    }
    encoder.finish();
    out.write(chunk.data(), chunk.size());
    table.points.push_back(last - first);
    table.bytes.push_back(chunk.size());
    at += chunk.size();
  }
  out.write(laz::encode_chunk_table(table, false));
  out.close();

  std::FILE* f = std::fopen(path.c_str(), "r+b");
  const auto offset = static_cast<std::int64_t>(at);
  const bool ok = f && fseeko(f, static_cast<off_t>(head.size()), SEEK_SET) == 0 && std::fwrite(&offset, 8, 1, f) == 1;
  if (f && std::fclose(f) != 0) throw Error(fmt::format("{}: cannot write the chunk table offset", name));
  if (!ok) throw Error(fmt::format("{}: cannot write the chunk table offset", name));
}

}  // namespace pointsurf::io::detail
